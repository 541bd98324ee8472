//! What a mesh's vertices carry for the asset they belong to and no method
//! reads: a skin's weights, morph target deltas, tangents (issue 49, items
//! 4 and 5). A fixed number of floats per vertex (or per wedge, where a
//! welded vertex's corners carry different ones), interpolated by every
//! collapse with the same parameter as UVs, kept by every move that keeps a
//! vertex, and copied where a vertex is split. Which float means what is the
//! scene's business (`scene::carry`).
//!
//! The first `hard` floats shape the surface as much as its UVs do (the
//! skin's weights, the targets' position deltas): corners whose hard floats
//! differ are a seam that collapses never cross. The rest are soft (normal
//! deltas, tangents): carried like normals, a faceted morphing model still
//! simplifies. The first `weights` of the hard floats are a skin's weights,
//! one per joint: a collapse never joins two vertices that share no joint
//! (bone boundaries, as Unreal's skeletal-mesh reduction keeps them).

/// `width` floats per item, the first `hard` of them shaping the surface,
/// the first `weights` of those joint weights.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Payload {
    pub width: usize,
    pub hard: usize,
    pub weights: usize,
    /// Item-major: item i's floats are `values[i·width..(i+1)·width]`.
    pub values: Vec<f32>,
}

impl Payload {
    /// No floats yet for items of `width` floats, the first `hard` hard,
    /// the first `weights` joint weights.
    pub fn new(width: usize, hard: usize, weights: usize) -> Self {
        let hard = hard.min(width);
        Payload {
            width,
            hard,
            weights: weights.min(hard),
            values: Vec::new(),
        }
    }

    /// A copy with no items.
    fn empty_like(&self) -> Payload {
        Payload::new(self.width, self.hard, self.weights)
    }

    /// How many items it holds (none for width 0).
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Item `i`'s floats.
    pub fn get(&self, i: usize) -> &[f32] {
        &self.values[i * self.width..(i + 1) * self.width]
    }

    /// Whether it holds floats for exactly `items` items.
    pub fn check(&self, what: &str, items: usize) -> Result<(), String> {
        match self.width > 0 && self.values.len() == items * self.width {
            true => Ok(()),
            false => Err(format!(
                "{} {what} floats for {items} items of {}",
                self.values.len(),
                self.width
            )),
        }
    }

    /// Appends item `a`'s floats interpolated towards `b`'s by `s` (exactly
    /// `a`'s at 0, `b`'s at 1: an item that stays keeps its bits).
    pub fn push_lerp(&mut self, a: usize, b: usize, s: f32) {
        let (a, b, s) = match s {
            0.0 => (a, a, 0.0),
            1.0 => (b, b, 0.0),
            _ => (a, b, s),
        };
        for k in 0..self.width {
            let (x, y) = (
                self.values[a * self.width + k],
                self.values[b * self.width + k],
            );
            self.values.push(x + (y - x) * s);
        }
    }

    /// Appends a copy of item `i`.
    pub fn push_copy(&mut self, i: usize) {
        self.push_lerp(i, i, 0.0);
    }

    /// Drops the last item.
    pub fn pop(&mut self) {
        let n = self.values.len().saturating_sub(self.width);
        self.values.truncate(n);
    }

    /// The items `order`, in that order.
    pub fn pick(&self, order: impl IntoIterator<Item = usize>) -> Payload {
        let mut out = self.empty_like();
        for i in order {
            out.values.extend_from_slice(self.get(i));
        }
        out
    }

    /// Keeps the items whose flag is set.
    pub fn retain(&mut self, keep: &[bool]) {
        let w = self.width;
        let mut next = 0;
        for (i, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
            self.values.copy_within(i * w..(i + 1) * w, next * w);
            next += 1;
        }
        self.values.truncate(next * w);
    }

    /// Whether items `a` and `b` hold the same hard floats (the same surface).
    pub fn same_hard(&self, a: usize, b: usize) -> bool {
        let w = self.width;
        self.values[a * w..a * w + self.hard] == self.values[b * w..b * w + self.hard]
    }

    /// Whether items `a` and `b` hold the same floats.
    pub fn same(&self, a: usize, b: usize) -> bool {
        self.get(a) == self.get(b)
    }

    /// Item `i`'s floats as bits, for hashing equal items together (+0.0
    /// and -0.0 alike).
    pub fn bits(&self, i: usize) -> Vec<u32> {
        self.get(i).iter().map(|x| (x + 0.0).to_bits()).collect()
    }

    /// Whether items `a` and `b` share a joint (a weight > 0 in both);
    /// always without weights.
    pub fn share_joint(&self, a: usize, b: usize) -> bool {
        let (x, y) = (self.get(a), self.get(b));
        self.weights == 0 || (0..self.weights).any(|k| x[k] > 0.0 && y[k] > 0.0)
    }

    /// `other`'s items after ours, or `None` where the layouts differ (the
    /// pieces of a mesh carry the same floats or the join carries none).
    pub fn joined(&self, other: &Payload) -> Option<Payload> {
        (self.empty_like() == other.empty_like()).then(|| Payload {
            values: [&self.values[..], &other.values[..]].concat(),
            ..self.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn three() -> Payload {
        Payload {
            values: vec![0.0, 1.0, 1.0, 3.0, 0.0, 5.0],
            ..Payload::new(2, 1, 0)
        }
    }

    #[test]
    fn items_interpolate_pick_and_retain() {
        let mut p = three();
        assert_eq!(p.len(), 3);
        p.push_lerp(0, 1, 0.25);
        assert_eq!(p.get(3), &[0.25, 1.5]);
        p.push_lerp(1, 0, 1.0);
        assert_eq!(p.get(4), &[0.0, 1.0], "exactly the end at s = 1");
        p.pop();
        assert_eq!(p.len(), 4);
        assert_eq!(p.pick([2, 0]).values, vec![0.0, 5.0, 0.0, 1.0]);
        p.retain(&[false, true, true, false]);
        assert_eq!(p.values, vec![1.0, 3.0, 0.0, 5.0]);
        assert!(p.check("x", 2).is_ok() && p.check("x", 3).is_err());
    }

    #[test]
    fn hard_floats_decide_the_surface() {
        let p = three();
        assert!(
            p.same_hard(0, 2) && !p.same(0, 2),
            "soft floats differ only"
        );
        assert!(!p.same_hard(0, 1));
        assert!(p.share_joint(0, 1), "no weights: no bone boundary");
        let q = Payload {
            values: vec![0.5, 0.5, 0.0, 1.0, 1.0, 0.0],
            ..Payload::new(2, 2, 2)
        };
        assert!(q.share_joint(0, 1) && q.share_joint(0, 2));
        assert!(!q.share_joint(1, 2), "disjoint joints");
        assert_eq!(p.joined(&q), None);
        assert_eq!(p.joined(&three()).map(|j| j.len()), Some(6));
    }
}
