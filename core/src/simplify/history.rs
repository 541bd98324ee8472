//! One edge collapse run forward only, with every triangle's lifetime: the
//! mesh after any number of its collapses is at hand, so an error search's
//! probes and an LOD chain's rows (issue 26) go back and forth along it
//! without cloning the collapser (the dragon's weighs 150 MB: its arrays
//! hold every vertex and triangle ever made) or collapsing again. Under an
//! error limit (module `limit`), raised row by row, the run skips what is
//! over the limit and its states are the phases' prefixes.
//!
//! Collapses never edit a triangle: they retire some and make new ones under
//! new ids, and never touch a vertex's position or attributes (a collapse
//! makes a new vertex). So state k (after k collapses) is the triangles born
//! at or before k and not yet dead, over the collapser's arrays.

use rayon::prelude::*;

use super::collapse::{EdgeCollapser, Veto};
use super::limit::Limit;
use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};

pub(super) struct History<'a> {
    collapser: EdgeCollapser,
    limit: Option<Limit<'a>>,
    /// Per triangle id: the state it appears in (0 for the input's).
    born: Vec<u32>,
    /// Per triangle id: the state it is gone in (`u32::MAX` while alive).
    died: Vec<u32>,
    /// Triangles alive in each state so far.
    counts: Vec<usize>,
}

impl<'a> History<'a> {
    /// `collapser` has made no collapse yet (state 0 is its start); it
    /// collapses only within `limit`, where one is given ([`History::raise`]).
    pub fn new(collapser: EdgeCollapser, limit: Option<Limit<'a>>) -> Self {
        debug_assert_eq!(collapser.collapses(), 0);
        let ever = collapser.arrays().triangles.len();
        // Triangles the collapser dropped before any collapse are dead from the start.
        let mut died = vec![0; ever];
        for t in collapser.alive_triangles() {
            died[t as usize] = u32::MAX;
        }
        History {
            born: vec![0; ever],
            died,
            counts: vec![collapser.triangle_count()],
            collapser,
            limit,
        }
    }

    /// Raises the error limit to `max_error`: the collapses it refused
    /// before are tried again as the run goes on.
    pub fn raise(&mut self, max_error: f32) {
        if let Some(limit) = &mut self.limit {
            limit.raise(max_error);
            self.collapser.readmit_vetoed();
        }
    }

    /// Lifts the error limit: the run goes on as an unlimited one would.
    pub fn lift(&mut self) {
        if self.limit.take().is_some() {
            self.collapser.readmit_vetoed();
        }
    }

    /// The collapser, at the last state reached.
    pub fn collapser(&self) -> &EdgeCollapser {
        &self.collapser
    }

    /// Triangles alive in state `k`.
    pub fn count(&self, k: usize) -> usize {
        self.counts[k]
    }

    /// The first state with at most `target` triangles, collapsing on as far
    /// as needed (the last state where nothing more collapses).
    pub fn reach(&mut self, target: usize, progress: &Progress) -> Result<usize, Cancelled> {
        if let Some(k) = self.counts.iter().position(|&c| c <= target) {
            return Ok(k);
        }
        progress.stage("collapsing edges");
        let from = self.collapser.triangle_count();
        let (born, died, counts) = (&mut self.born, &mut self.died, &mut self.counts);
        let mut cancelled = false;
        let veto = self.limit.as_mut().map(|l| l as &mut dyn Veto);
        self.collapser.run_vetted(target, veto, |s, c| {
            let k = s.collapses() as u32;
            for &t in &c.removed {
                died[t as usize] = k;
            }
            for &t in &c.added {
                debug_assert_eq!(t as usize, born.len(), "ids are handed out in order");
                born.push(k);
                died.push(u32::MAX);
            }
            counts.push(s.triangle_count());
            if s.collapses().is_multiple_of(512) {
                let done =
                    (from - s.triangle_count()) as f32 / from.saturating_sub(target).max(1) as f32;
                progress.set_fraction(done);
                cancelled = progress.is_cancelled();
                if progress.wants_preview() {
                    progress.publish(crate::lod::DrawSet {
                        mesh: s.mesh().0,
                        ..Default::default()
                    });
                }
            }
            !cancelled
        });
        progress.check()?;
        Ok(self.counts.len() - 1)
    }

    /// The mesh of state `k` (compacted) and the collapser's id of each of
    /// its triangles, ascending.
    pub fn mesh_at(&self, k: usize) -> (TriMesh, Vec<u32>) {
        debug_assert!(k < self.counts.len(), "state {k} not reached");
        let k = k as u32;
        // Every triangle ever made is tested (3.5M on the dragon): in
        // parallel, collected in order.
        let (born, died) = (&self.born, &self.died);
        let ids: Vec<u32> = (0..born.len() as u32)
            .into_par_iter()
            .filter(|&t| born[t as usize] <= k && k < died[t as usize])
            .collect();
        (self.collapser.arrays().gather(ids.iter().copied()), ids)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplify::CollapseOptions;

    /// Any state looked up going back equals a fresh collapser run to it
    /// (mesh, ids, count), and reaching a count twice runs nothing.
    #[test]
    fn a_past_state_is_a_fresh_run_to_it() {
        let mesh = crate::builtins::torus(1.0, 0.3, 48, 24);
        let fresh = || EdgeCollapser::new(&mesh, CollapseOptions::default());
        let mut history = History::new(fresh(), None);
        let p = Progress::new();
        let n = mesh.triangles.len();
        let deepest = history.reach(n / 16, &p).unwrap();
        for target in [n, n / 2, n / 3, n / 7, n / 16] {
            let k = history.reach(target, &p).unwrap();
            let mut run = fresh();
            run.run(target, |_, _| true);
            assert_eq!(k, run.collapses(), "{target}");
            assert_eq!(history.count(k), run.triangle_count());
            assert_eq!(history.mesh_at(k), run.mesh(), "{target}");
        }
        assert_eq!(history.reach(n / 16, &p).unwrap(), deepest);
        assert_eq!(history.counts.len(), deepest + 1, "nothing ran again");
    }
}
