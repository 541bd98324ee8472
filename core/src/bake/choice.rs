//! Whether a LOD bakes when its row says neither `bake` nor `no bake`
//! (issue 50: "automatic when the budget cannot be met within the UV
//! tolerance", and wherever a bake looks closer to the original).
//!
//! Two reasons, in order:
//! 1. **Seams**: the LOD is short of its triangle budget because its seams
//!    stay (`unmet`'s first rule). Baked, they are free.
//! 2. **Measured**: the same count built free of seams and baked looks
//!    closer to the original than the LOD keeping the original's atlas.
//!    Only where the bake loses nothing else: its one material keeps what
//!    the original's share ([`bakes_losslessly`]), and the budget is a
//!    count (an error budget met free of seams is a coarser LOD, which
//!    this measure, blind to geometry, would favour).
//!    A collapse that keeps the atlas interpolates the original's normals
//!    across creases and its UVs across charts; a bake transfers both
//!    exactly, at the cost of its texels' resolution. Which wins depends on
//!    the model and the count (the truck at half its triangles: baked;
//!    a smooth, normal-mapped model: the atlas), so it is measured.
//!
//! **The measure** ([`appearance_psnr`]): at area-uniform points of a
//! candidate, what it shows against what the original shows at the nearest
//! point (`io::appearance`: colour and normal-mapped shading normal), as
//! half-Lambert shading `c (1 + n·l) / 2` under a light from a uniformly
//! random direction `l`. Its mean squared difference has a closed form,
//! E[(Δc + (c₁n₁ − c₂n₂)·l)²] / 4 = (Δc² + |c₁n₁ − c₂n₂|² / 3) / 4 per
//! channel (E[l] = 0, E[l lᵀ] = I/3), so no light is sampled. It is given
//! as a PSNR in dB over the linear [0, 1] range, like `compare`'s.

use super::{Baked, bake};
use crate::distance::{MeshDistance, barycentric};
use crate::geom::TriMesh;
use crate::io::appearance::Appearance;
use crate::lod::{Blocker, Unmet};
use crate::rng::Rng;

/// Points measured per candidate: the decision's PSNRs move by under
/// 0.05 dB between seeds at this count (truck, ClearCoat).
const SAMPLES: usize = 32_768;

/// The two candidates' measured likeness to the original.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Measured {
    /// The LOD keeping the original's atlas, in dB ([`appearance_psnr`]).
    pub kept_db: f64,
    /// The same count free of seams and baked, in dB.
    pub baked_db: f64,
}

/// Whether the original wears a texture.
pub fn textured(original: &TriMesh) -> bool {
    original
        .materials
        .as_ref()
        .is_some_and(|m| m.table.iter().any(|m| m.base_color_texture.is_some()))
}

/// Whether a bake's one material loses nothing of the original's: they
/// differ at most in what a bake transfers (base colour, its texture,
/// normal maps) and their names.
fn bakes_losslessly(original: &TriMesh) -> bool {
    let rest = |m: &crate::geom::Material| {
        (
            m.metallic,
            m.roughness,
            m.emissive,
            m.alpha_mode,
            m.double_sided,
            m.base_color[3],
        )
    };
    let table = original
        .materials
        .as_ref()
        .map_or(&[][..], |m| &m.table[..]);
    table.windows(2).all(|w| rest(&w[0]) == rest(&w[1]))
}

/// Whether a LOD of `original` is short of its triangle budget because its
/// seams stay (`unmet`'s most common rule) and a baked texture of its own
/// would free them: the original is textured.
pub fn short_of_seams(original: &TriMesh, unmet: Option<&Unmet>) -> bool {
    textured(original)
        && unmet.is_some_and(|u| u.blockers.first().is_some_and(|b| b.0 == Blocker::Seams))
}

/// How alike `candidate` looks to the original (module doc), in dB;
/// `nearest` is the original's distance structure.
pub fn appearance_psnr(original: &Appearance, nearest: &MeshDistance, candidate: &TriMesh) -> f64 {
    let shown = Appearance::new(candidate);
    let mut cdf = Vec::with_capacity(candidate.triangles.len());
    let mut total = 0.0f64;
    for t in 0..candidate.triangles.len() {
        total += candidate.triangle_area(t) as f64;
        cdf.push(total);
    }
    if total <= 0.0 {
        return 0.0;
    }
    let mut rng = Rng::new(1);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for _ in 0..SAMPLES {
        let x = rng.f32() as f64 * total;
        let t = cdf.partition_point(|c| *c <= x).min(cdf.len() - 1);
        let (mut u, mut v) = (rng.f32(), rng.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let b = [1.0 - u - v, u, v];
        let [p0, p1, p2] = candidate.triangle(t);
        let p = p0 * b[0] + p1 * b[1] + p2 * b[2];
        let Some((q, o)) = nearest.closest(p) else {
            continue;
        };
        let [a, bb, cc] = nearest.mesh.triangle(o as usize);
        let at = barycentric(q, a, bb, cc);
        let (c1, n1) = (shown.color(t, b), shown.normal(t, b));
        let (c2, n2) = (
            original.color(o as usize, at),
            original.normal(o as usize, at),
        );
        let dc = c1 - c2;
        let lit = [0, 1, 2].map(|k| (n1 * c1[k] - n2 * c2[k]).length_squared());
        sum += (0..3)
            .map(|k| (dc[k] * dc[k] + lit[k] / 3.0) as f64 / 4.0)
            .sum::<f64>()
            / 3.0;
        n += 1;
    }
    let mse = sum / n.max(1) as f64;
    -10.0 * mse.max(1e-12).log10()
}

/// What a row asked for and got, as the choice reads it.
pub struct Asked<'a> {
    /// The kept LOD's unmet budget, if any.
    pub unmet: Option<&'a Unmet>,
    /// Whether its budget is a triangle count of a collapse (the free
    /// candidate is then the same count).
    pub count: bool,
    /// The baked texture's side, if the row gives one.
    pub size: Option<u32>,
}

/// For a LOD (`kept`, keeping the original's atlas) whose row says neither
/// `bake` nor `no bake`: the same count built free of seams (`free`) and
/// baked at `size` (or [`default_size`](super::default_size)), when
/// seams keep it short or, for a `count` budget, the module doc's reasons say so; `None` to keep
/// `kept`. A bake that fails is an error only where seams left no choice.
///
/// # Errors
/// `free`'s error, or a failed bake (through `bake_error`) of a LOD short
/// of seams.
pub fn bake_unasked<T, E>(
    original: &TriMesh,
    kept: &TriMesh,
    asked: Asked<'_>,
    free: impl FnOnce() -> Result<T, E>,
    mesh_of: impl Fn(&T) -> &TriMesh,
    bake_error: impl FnOnce(String) -> E,
) -> Result<Option<(T, Baked)>, E> {
    if !textured(original) || kept.triangles.is_empty() {
        return Ok(None);
    }
    let short = short_of_seams(original, asked.unmet);
    if !(short || (asked.count && bakes_losslessly(original))) {
        return Ok(None);
    }
    let candidate = free()?;
    let lod = mesh_of(&candidate);
    let size = asked
        .size
        .unwrap_or_else(|| super::default_size(original, lod.triangles.len()));
    let baked = match bake(original, lod, size) {
        Ok(b) => b,
        Err(e) if short => return Err(bake_error(e)),
        Err(_) => return Ok(None),
    };
    let measured = match short {
        true => None,
        false => {
            let (appearance, nearest) = (Appearance::new(original), MeshDistance::new(original));
            let m = Measured {
                kept_db: appearance_psnr(&appearance, &nearest, kept),
                baked_db: appearance_psnr(&appearance, &nearest, &baked.mesh),
            };
            if m.baked_db <= m.kept_db {
                return Ok(None);
            }
            Some(m)
        }
    };
    let report = super::BakeReport {
        automatic: true,
        measured,
        ..baked.report
    };
    Ok(Some((candidate, Baked { report, ..baked })))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// A surface measured against itself is as alike as it gets; a copy
    /// whose normals turn away and whose colour darkens measures worse, by
    /// the closed form's amount.
    #[test]
    fn the_measure_is_the_closed_form() {
        let mut square = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        square.normals = Some(vec![Vec3::Z; 4]);
        let (appearance, nearest) = (Appearance::new(&square), MeshDistance::new(&square));
        assert!(appearance_psnr(&appearance, &nearest, &square) >= 119.0);
        let mut turned = square.clone();
        turned.normals = Some(vec![Vec3::X; 4]);
        // White both, normals 90° apart: |n₁ − n₂|² / 3 / 4 = 2 / 12.
        let want = -10.0 * (2.0f64 / 12.0).log10();
        let got = appearance_psnr(&appearance, &nearest, &turned);
        assert!((got - want).abs() < 1e-3, "{got} vs {want}");
    }
}
