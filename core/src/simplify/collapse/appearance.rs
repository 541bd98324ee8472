//! Attribute-aware collapse order: the appearance a collapse loses, as a
//! length, added to its geometric cost (Hoppe, "New quadric metric for
//! simplifying meshes with appearance attributes", 1999; meshoptimizer's
//! `simplifyWithAttributes`). The certified bound stays geometric: this
//! only reorders the collapses, so that the ones that keep normals,
//! texture coordinates and colours go first at equal geometric cost.
//!
//! Each end that moves is looked at where it was: the attributes the new
//! fan interpolates at its old position (on the nearest new triangle)
//! against the ones its own corner had there. Attributes varying linearly
//! across the fan cost nothing; a lost peak, crease or texture detail
//! costs its size. Each difference becomes a length: a normal turned by
//! |Δn| over the distance ℓ the vertex moves is a surface bent by about
//! |Δn|·ℓ; a colour likewise; a UV off by |Δuv| shows a texel that far on
//! the surface, |Δuv| times the triangle's length per UV unit (Cohen et
//! al.'s texture deviation). The weights scale each length; 0 leaves an
//! attribute out.

use glam::{Vec2, Vec3};

use super::{Candidate, EdgeCollapser, edge_parameter};
use crate::distance::{barycentric, closest_point_on_triangle};
use crate::geom::Wedges;

/// Weights of the appearance lengths in the collapse order. All 0 by
/// default: on the truck a normal weight of 0.25 raised the PSNR at 1,000
/// and 700 triangles by 0.3–0.9 dB, but on the horse even 0.05 made the
/// certified bound at 10 % 3.7× larger (BENCHMARKS.md); geometry first,
/// appearance where the user asks for it.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct AttributeWeights {
    pub normal: f32,
    pub uv: f32,
    pub color: f32,
}

/// Each weight's range.
pub const ATTRIBUTE_WEIGHT_RANGE: std::ops::RangeInclusive<f32> = 0.0..=100.0;

impl AttributeWeights {
    /// Every weight inside [`ATTRIBUTE_WEIGHT_RANGE`].
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        use crate::lod::in_range;
        in_range("normal weight", self.normal, &ATTRIBUTE_WEIGHT_RANGE)?;
        in_range("uv weight", self.uv, &ATTRIBUTE_WEIGHT_RANGE)?;
        in_range("color weight", self.color, &ATTRIBUTE_WEIGHT_RANGE)
    }

    /// Parses `normal=W,uv=W,color=W` (any subset; the rest stay 0).
    pub fn parse(text: &str) -> Result<AttributeWeights, String> {
        let mut w = AttributeWeights::default();
        for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let (name, value) = item
                .split_once('=')
                .ok_or_else(|| format!("expected NAME=WEIGHT, got {item:?}"))?;
            let value: f32 = value
                .trim()
                .parse()
                .map_err(|_| format!("{name}: {value:?} is not a number"))?;
            match name.trim() {
                "normal" => w.normal = value,
                "uv" => w.uv = value,
                "color" | "colour" => w.color = value,
                other => return Err(format!("{other:?} is none of normal, uv, color")),
            }
        }
        w.validate().map_err(|e| e.to_string())?;
        Ok(w)
    }

    fn is_zero(&self) -> bool {
        self.normal == 0.0 && self.uv == 0.0 && self.color == 0.0
    }
}

/// One corner's attributes (zero where the mesh has none).
#[derive(Clone, Copy, Default)]
struct Attributes {
    normal: Vec3,
    color: Vec3,
    uv: Vec2,
}

impl Attributes {
    fn lerp(self, o: Attributes, s: f32) -> Attributes {
        Attributes {
            normal: self.normal.lerp(o.normal, s).normalize_or(self.normal),
            color: self.color.lerp(o.color, s),
            uv: self.uv.lerp(o.uv, s),
        }
    }

    fn blend(c: [Attributes; 3], b: [f32; 3]) -> Attributes {
        Attributes {
            normal: (c[0].normal * b[0] + c[1].normal * b[1] + c[2].normal * b[2])
                .normalize_or(c[0].normal),
            color: c[0].color * b[0] + c[1].color * b[1] + c[2].color * b[2],
            uv: c[0].uv * b[0] + c[1].uv * b[1] + c[2].uv * b[2],
        }
    }
}

/// The attributes of wedge `i` of `w`.
fn wedge_attributes(w: &Wedges, i: u32) -> Attributes {
    let i = i as usize;
    Attributes {
        normal: w.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]),
        color: w.colors.as_ref().map_or(Vec3::ZERO, |c| c[i]),
        uv: w.uvs.as_ref().map_or(Vec2::ZERO, |u| u[i]),
    }
}

impl EdgeCollapser {
    /// The attributes of triangle `t`'s corner at `v`: its wedge's, or the
    /// vertex's where the mesh has no wedges.
    fn corner_attributes(&self, t: u32, v: u32) -> Attributes {
        match &self.wedges {
            Some(w) => wedge_attributes(w, self.wedge_at(w, t, v)),
            None => Attributes {
                normal: self.normal(v).unwrap_or(Vec3::ZERO),
                color: self.color(v).unwrap_or(Vec3::ZERO),
                uv: self.uv(v).unwrap_or(Vec2::ZERO),
            },
        }
    }

    /// What the new vertex's corner in the triangle that was `t` holds
    /// when `end` (side 0: the edge's first end) moves and the edge
    /// collapses at parameter `s`: `end`'s corner interpolated towards its
    /// partner across the edge (`map_wedges`' rule), kept where it has none.
    fn new_corner(
        &self,
        t: u32,
        (end, other): (u32, u32),
        side: usize,
        s: f32,
        pairs: &[(u32, u32)],
    ) -> Attributes {
        let own = self.corner_attributes(t, end);
        let partner = match &self.wedges {
            Some(w) => Self::partner(w, pairs, side, self.wedge_at(w, t, end))
                .map(|q| wedge_attributes(w, q)),
            None => Some(Attributes {
                normal: self.normal(other).unwrap_or(Vec3::ZERO),
                color: self.color(other).unwrap_or(Vec3::ZERO),
                uv: self.uv(other).unwrap_or(Vec2::ZERO),
            }),
        };
        let towards = if side == 0 { s } else { 1.0 - s };
        partner.map_or(own, |q| own.lerp(q, towards))
    }

    /// The squared appearance length of collapsing `cand` (module doc).
    pub(crate) fn appearance_squared(&self, cand: &Candidate) -> f32 {
        let weights = self.opts.attribute_weights;
        if weights.is_zero()
            || self.normals.is_none() && self.colors.is_none() && self.uvs.is_none()
        {
            return 0.0;
        }
        let [a, b] = cand.edge;
        let p = cand.position;
        let s = edge_parameter(self.pos[a as usize], self.pos[b as usize], p);
        let (pairs, n) = match &self.wedges {
            Some(w) => self
                .wedge_pairs(w, a, b)
                .unwrap_or(([(u32::MAX, u32::MAX); 4], 0)),
            None => ([(u32::MAX, u32::MAX); 4], 0),
        };
        let pairs = &pairs[..n];
        let mut worst = 0.0f32;
        for (end, other, side) in [(a, b, 0usize), (b, a, 1usize)] {
            let pe = self.pos[end as usize];
            let moved = pe.distance(p);
            if moved == 0.0 {
                continue;
            }
            // The nearest new triangle to where `end` was.
            let mut nearest = (f32::INFINITY, 0u32, [0.0f32; 3]);
            for &t in &self.vtris[end as usize] {
                let tri = self.tris[t as usize];
                if tri.contains(&other) {
                    continue;
                }
                let x = tri.map(|w| if w == end { p } else { self.pos[w as usize] });
                let q = closest_point_on_triangle(pe, x[0], x[1], x[2]);
                let d = q.distance_squared(pe);
                if d < nearest.0 {
                    nearest = (d, t, barycentric(q, x[0], x[1], x[2]));
                }
            }
            if !nearest.0.is_finite() {
                continue;
            }
            let (_, t, bary) = nearest;
            let tri = self.tris[t as usize];
            let corners = tri.map(|w| match w == end {
                true => self.new_corner(t, (end, other), side, s, pairs),
                false => self.corner_attributes(t, w),
            });
            let fit = Attributes::blend(corners, bary);
            let was = self.corner_attributes(t, end);
            let x = self.triangle_positions(t);
            let u = tri.map(|w| self.corner_attributes(t, w).uv);
            let area = (x[1] - x[0]).cross(x[2] - x[0]).length();
            let area_uv = (u[1] - u[0]).perp_dot(u[2] - u[0]).abs();
            let per_uv = if area_uv > 0.0 {
                (area / area_uv).sqrt()
            } else {
                0.0
            };
            let normal = weights.normal * fit.normal.distance(was.normal) * moved;
            let color = weights.color * fit.color.distance(was.color) * moved;
            let uv = weights.uv * fit.uv.distance(was.uv) * per_uv;
            worst = worst.max(normal * normal + color * color + uv * uv);
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::TriMesh;
    use crate::simplify::CollapseOptions;

    /// A flat n×n grid of the unit square coloured by `color(x, y)`.
    fn grid(n: u32, color: impl Fn(f32, f32) -> Vec3) -> TriMesh {
        let mut m = crate::simplify::collapse::tests::height_grid(n, |_, _| 0.0);
        m.colors = Some(m.positions.iter().map(|p| color(p.x, p.y)).collect());
        m
    }

    fn colour_weighted(w: f32) -> CollapseOptions {
        CollapseOptions {
            attribute_weights: AttributeWeights {
                color: w,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    #[test]
    fn a_linear_colour_costs_nothing_and_a_lost_peak_its_size() {
        let ramp = grid(8, |x, y| Vec3::new(x, y, 0.5));
        let col = EdgeCollapser::new(&ramp, colour_weighted(1.0));
        let centre = 4 * 9 + 4;
        let peaked = {
            let mut m = ramp.clone();
            m.colors.as_mut().unwrap()[centre] = Vec3::ONE;
            m
        };
        let peak = EdgeCollapser::new(&peaked, colour_weighted(1.0));
        // The centre moves onto its right-hand neighbour.
        let to_neighbour = |col: &EdgeCollapser| {
            let cand = Candidate {
                edge: [centre as u32, centre as u32 + 1],
                position: col.position(centre as u32 + 1),
                quadric_error: 0.0,
                quadric_weight: 1.0,
                triangles_removed: 2,
            };
            col.appearance_squared(&cand).sqrt()
        };
        // Interpolated across the new fan, a ramp is what it was.
        assert!(to_neighbour(&col) < 1e-6, "{}", to_neighbour(&col));
        // The peak is lost: where it was, the fan shows the ramp's
        // (½, ½, ½), √3/2 from white, over the 1/8 it moved.
        let lost = 3f32.sqrt() / 2.0 / 8.0;
        let got = to_neighbour(&peak);
        assert!((got - lost).abs() < 1e-4, "{got} vs {lost}");
        // Weights parse by name, keep the rest at 0 and refuse nonsense.
        let w = AttributeWeights::parse("normal=0.25, uv=2").unwrap();
        assert_eq!((w.normal, w.uv, w.color), (0.25, 2.0, 0.0));
        for bad in ["normal", "normal=x", "shine=1", "uv=-1", "color=1e9"] {
            assert!(AttributeWeights::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_colour_weight_keeps_a_coloured_detail_the_geometry_does_not_see() {
        // A flat square: every collapse costs 0 geometrically, so only the
        // appearance decides which vertices go.
        let n = 16;
        let spot = Vec3::new(0.5, 0.5, 0.0);
        let mesh = grid(n, |x, y| match Vec3::new(x, y, 0.0).distance(spot) < 0.1 {
            true => Vec3::new(1.0, 0.0, 0.0),
            false => Vec3::splat(0.5),
        });
        let red = |w: f32| {
            let mut col = EdgeCollapser::new(&mesh, colour_weighted(w));
            col.run(mesh.triangles.len() / 8, |_, _| true);
            let out = col.mesh().0;
            out.colors
                .unwrap()
                .iter()
                .filter(|c| c.x > 0.9 && c.y < 0.1)
                .count()
        };
        // The red spot's vertices: 9 at distance < 0.1 on a 1/16 grid.
        assert!(red(1.0) >= 4, "{}", red(1.0));
        assert!(red(0.0) < red(1.0), "{} vs {}", red(0.0), red(1.0));
    }
}
