//! Implicit solids as signed distance bounds (negative inside): the inputs of the
//! voxel method and the source of the `sphereflake` and `csg-part` built-ins.
//!
//! CSG with min/max keeps the value a bound on the true distance, which is what
//! sampling and the iso-surface need (the sign is exact).

use glam::Vec3;

use crate::geom::Aabb;

/// A solid given by a function that is negative inside and positive outside.
pub trait Implicit: Send + Sync {
    fn value(&self, p: Vec3) -> f32;
    fn bounds(&self) -> Aabb;
    /// `Some(inside)` when the whole box (`center` ± `half`) is on one side of
    /// the surface; lets the sampler skip the box voxel by voxel.
    fn classify_block(&self, center: Vec3, half: Vec3) -> Option<bool> {
        let v = self.value(center);
        (v.abs() > half.length()).then_some(v < 0.0)
    }
    /// The surface itself, where the solid is a mesh's (what simplified
    /// levels are certified against).
    fn surface(&self) -> Option<&crate::geom::TriMesh> {
        None
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Implicit for Sphere {
    fn value(&self, p: Vec3) -> f32 {
        p.distance(self.center) - self.radius
    }
    fn bounds(&self) -> Aabb {
        Aabb {
            min: self.center - Vec3::splat(self.radius),
            max: self.center + Vec3::splat(self.radius),
        }
    }
}

/// The sphereflake of the voxel paper: a sphere with nine children of a third of
/// its radius touching it, recursively; depth 3 gives 1 + 9 + 81 + 729 = 820 spheres.
#[derive(Debug, Clone, PartialEq)]
pub struct Sphereflake {
    /// Depth-first order; `children[i]` lists the indices of sphere i's children.
    pub spheres: Vec<Sphere>,
    children: Vec<Vec<u32>>,
    /// Radius of a sphere enclosing sphere i and all its descendants.
    reach: Vec<f32>,
}

impl Sphereflake {
    pub fn new(depth: u32) -> Sphereflake {
        let mut flake = Sphereflake {
            spheres: Vec::new(),
            children: Vec::new(),
            reach: Vec::new(),
        };
        flake.add(Vec3::ZERO, 1.0, Vec3::Z, depth);
        flake
    }

    fn add(&mut self, center: Vec3, radius: f32, up: Vec3, depth: u32) -> u32 {
        let id = self.spheres.len() as u32;
        self.spheres.push(Sphere { center, radius });
        self.children.push(Vec::new());
        // A subtree reaches at most r(1 + 2/3 + 2/9 + ...) = 3r from the centre.
        self.reach.push(3.0 * radius);
        if depth == 0 {
            return id;
        }
        let (u, v) = up.any_orthonormal_pair();
        let child_r = radius / 3.0;
        // Six children around the equator and three above it, offset by 30°.
        let mut dirs = Vec::with_capacity(9);
        for k in 0..6 {
            let a = k as f32 * std::f32::consts::FRAC_PI_3;
            dirs.push(u * a.cos() + v * a.sin());
        }
        let elev = 60f32.to_radians();
        for k in 0..3 {
            let a = k as f32 * 2.0 * std::f32::consts::FRAC_PI_3 + std::f32::consts::FRAC_PI_6;
            dirs.push(((u * a.cos() + v * a.sin()) * elev.cos() + up * elev.sin()).normalize());
        }
        for d in dirs {
            let c = self.add(center + d * (radius + child_r), child_r, d, depth - 1);
            self.children[id as usize].push(c);
        }
        id
    }

    fn value_from(&self, i: usize, p: Vec3, best: f32) -> f32 {
        let s = self.spheres[i];
        let mut best = best.min(s.value(p));
        for &c in &self.children[i] {
            let cs = self.spheres[c as usize];
            // Skip subtrees that cannot beat the best value found so far.
            if p.distance(cs.center) - self.reach[c as usize] < best {
                best = self.value_from(c as usize, p, best);
            }
        }
        best
    }
}

impl Implicit for Sphereflake {
    fn value(&self, p: Vec3) -> f32 {
        self.value_from(0, p, f32::INFINITY)
    }
    fn bounds(&self) -> Aabb {
        self.spheres
            .iter()
            .fold(Aabb::EMPTY, |b, s| b.union(s.bounds()))
    }
}

/// Constructive solid geometry over primitive solids.
#[derive(Debug, Clone, PartialEq)]
pub enum Csg {
    /// Axis-aligned box.
    Cuboid {
        min: Vec3,
        max: Vec3,
    },
    /// Cylinder along z between `z0` and `z1`.
    CylinderZ {
        center: Vec3,
        radius: f32,
        z0: f32,
        z1: f32,
    },
    /// Cylinder along x between `x0` and `x1`.
    CylinderX {
        center: Vec3,
        radius: f32,
        x0: f32,
        x1: f32,
    },
    Union(Vec<Csg>),
    /// The first solid minus all the others.
    Difference(Box<Csg>, Vec<Csg>),
}

/// Distance to a 2D rectangle-extruded shape: combines an in-plane distance and an
/// axial interval into a box-like signed distance.
fn extrude(d2: f32, p: f32, lo: f32, hi: f32) -> f32 {
    let dz = (lo - p).max(p - hi);
    let outside = glam::Vec2::new(d2.max(0.0), dz.max(0.0)).length();
    outside + d2.max(dz).min(0.0)
}

impl Implicit for Csg {
    fn value(&self, p: Vec3) -> f32 {
        match self {
            Csg::Cuboid { min, max } => {
                let c = (*min + *max) * 0.5;
                let h = (*max - *min) * 0.5;
                let q = (p - c).abs() - h;
                q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
            }
            Csg::CylinderZ {
                center,
                radius,
                z0,
                z1,
            } => {
                let d2 = glam::Vec2::new(p.x - center.x, p.y - center.y).length() - radius;
                extrude(d2, p.z, *z0, *z1)
            }
            Csg::CylinderX {
                center,
                radius,
                x0,
                x1,
            } => {
                let d2 = glam::Vec2::new(p.y - center.y, p.z - center.z).length() - radius;
                extrude(d2, p.x, *x0, *x1)
            }
            Csg::Union(parts) => parts
                .iter()
                .map(|s| s.value(p))
                .fold(f32::INFINITY, f32::min),
            Csg::Difference(base, holes) => holes
                .iter()
                .map(|h| -h.value(p))
                .fold(base.value(p), f32::max),
        }
    }

    fn bounds(&self) -> Aabb {
        match self {
            Csg::Cuboid { min, max } => Aabb {
                min: *min,
                max: *max,
            },
            Csg::CylinderZ {
                center,
                radius,
                z0,
                z1,
            } => Aabb {
                min: Vec3::new(center.x - radius, center.y - radius, *z0),
                max: Vec3::new(center.x + radius, center.y + radius, *z1),
            },
            Csg::CylinderX {
                center,
                radius,
                x0,
                x1,
            } => Aabb {
                min: Vec3::new(*x0, center.y - radius, center.z - radius),
                max: Vec3::new(*x1, center.y + radius, center.z + radius),
            },
            Csg::Union(parts) => parts.iter().fold(Aabb::EMPTY, |b, s| b.union(s.bounds())),
            Csg::Difference(base, _) => base.bounds(),
        }
    }
}

/// The `csg-part`: a plate with a boss, three through-holes (one through the boss),
/// a hole cross-drilled through both walls of the boss and a blind pocket:
/// genus 5 (two plate holes, the bore, and two openings of the cross hole).
pub fn csg_part() -> Csg {
    let plate = Csg::Cuboid {
        min: Vec3::new(-2.0, -1.0, -0.3),
        max: Vec3::new(2.0, 1.0, 0.3),
    };
    let boss = Csg::CylinderZ {
        center: Vec3::new(1.2, 0.0, 0.0),
        radius: 0.7,
        z0: -0.3,
        z1: 1.0,
    };
    let hole = |x: f32, y: f32, r: f32| Csg::CylinderZ {
        center: Vec3::new(x, y, 0.0),
        radius: r,
        z0: -1.0,
        z1: 2.0,
    };
    Csg::Difference(
        Box::new(Csg::Union(vec![plate, boss])),
        vec![
            hole(-1.3, 0.0, 0.35),
            hole(-0.2, 0.45, 0.25),
            hole(1.2, 0.0, 0.3),
            // Cross hole through the boss wall above the plate.
            Csg::CylinderX {
                center: Vec3::new(0.0, 0.0, 0.7),
                radius: 0.15,
                x0: 0.3,
                x1: 2.1,
            },
            // Blind pocket: no genus.
            Csg::Cuboid {
                min: Vec3::new(-0.6, -0.8, 0.1),
                max: Vec3::new(0.2, -0.3, 0.5),
            },
        ],
    )
}

/// A triangle mesh as a solid: inside where its generalised winding number is at
/// least ½ in magnitude, so open and self-overlapping meshes (the bunny's open
/// base, CAD assemblies) and inward-oriented ones (the horse) sample sensibly; |value| is the exact distance to the surface, which
/// keeps the [`Implicit`] contract the sampler relies on.
pub struct MeshSolid<'a> {
    winding: crate::distance::WindingNumber<'a>,
    mesh: &'a crate::geom::TriMesh,
    bounds: Aabb,
}

impl<'a> MeshSolid<'a> {
    pub fn new(mesh: &'a crate::geom::TriMesh) -> Self {
        Self {
            winding: crate::distance::WindingNumber::new(mesh),
            mesh,
            bounds: mesh.bounds(),
        }
    }
}

impl Implicit for MeshSolid<'_> {
    fn value(&self, p: Vec3) -> f32 {
        let d = self.winding.distance(p);
        if self.winding.winding(p).abs() >= 0.5 {
            -d
        } else {
            d
        }
    }
    fn bounds(&self) -> Aabb {
        self.bounds
    }
    fn surface(&self) -> Option<&crate::geom::TriMesh> {
        Some(self.mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meshes_are_solid_whichever_way_they_face() {
        let torus = crate::builtins::torus(1.0, 0.35, 32, 16);
        let mut inward = torus.clone();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        for mesh in [&torus, &inward] {
            let solid = MeshSolid::new(mesh);
            assert!(
                (solid.value(Vec3::new(1.0, 0.0, 0.0)) + 0.35).abs() < 0.01,
                "inside the tube"
            );
            assert!(solid.value(Vec3::ZERO) > 0.6, "in the hole");
        }
    }

    #[test]
    fn sphereflake_has_820_spheres_that_do_not_overlap_their_parent() {
        let f = Sphereflake::new(3);
        assert_eq!(f.spheres.len(), 820);
        for (i, kids) in f.children.iter().enumerate() {
            for &c in kids {
                let (p, k) = (f.spheres[i], f.spheres[c as usize]);
                let gap = p.center.distance(k.center) - p.radius - k.radius;
                assert!(gap.abs() < 1e-5, "children touch their parent");
            }
        }
        // The pruned recursive evaluation equals the brute-force minimum.
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..2000 {
            let p = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0 - Vec3::splat(2.0);
            let brute = f
                .spheres
                .iter()
                .map(|s| s.value(p))
                .fold(f32::INFINITY, f32::min);
            assert!((f.value(p) - brute).abs() < 1e-6);
        }
    }

    #[test]
    fn csg_signs() {
        let part = csg_part();
        assert!(part.value(Vec3::new(0.5, -0.9, 0.0)) < 0.0, "in the plate");
        assert!(part.value(Vec3::new(-1.3, 0.0, 0.0)) > 0.0, "in a hole");
        assert!(
            part.value(Vec3::new(1.2, 0.6, 0.7)) < 0.0,
            "in the boss wall"
        );
        assert!(
            part.value(Vec3::new(0.7, 0.0, 0.7)) > 0.0,
            "in the cross hole"
        );
        assert!(part.value(Vec3::new(0.0, 0.0, 3.0)) > 0.0, "outside");
    }
}
