//! The cut of a tileset a 3D Tiles viewer draws (3D Tiles 1.1, "Geometric
//! error" and "Refinement"): from the root, a tile seen by the camera is
//! refined when its screen-space error, `geometricError · focal / d` with
//! `d` the distance from the eye to its bounding volume, is above the
//! viewer's maximum (CesiumJS's `maximumScreenSpaceError`, 16 px by
//! default); `REPLACE` draws its children instead, `ADD` with it. With
//! lodstudio's certified errors, every drawn tile is then within that many
//! pixels of the original surface.

use super::tileset::Tileset;
use crate::view::View;

/// One tile of a cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drawn {
    pub tile: usize,
    /// Its screen-space error in pixels (∞ with the eye in its volume).
    pub sse_px: f32,
}

/// A tile's screen-space error from `view`.
pub fn sse_px(set: &Tileset, tile: usize, view: &View) -> f32 {
    let t = &set.tiles[tile];
    let d = t.bounds.distance(view.eye);
    if d <= 0.0 {
        return f32::INFINITY;
    }
    t.error * view.focal_pixels() / d
}

/// The tiles `view` draws at `max_sse_px`, into `out` (cleared; kept
/// between frames so a cut allocates nothing once it has grown), in
/// depth-first order; tiles outside the view are culled with all below them.
pub fn cut(set: &Tileset, view: &View, max_sse_px: f32, out: &mut Vec<Drawn>) {
    out.clear();
    if set.tiles.is_empty() {
        return;
    }
    let test = view.sphere_test();
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let t = &set.tiles[i];
        let (c, r) = (t.bounds.center(), 0.5 * t.bounds.diagonal());
        if !test.sees(c, r) {
            continue;
        }
        let sse = sse_px(set, i, view);
        let refine = sse > max_sse_px && !t.children.is_empty();
        if !refine || t.add {
            out.push(Drawn {
                tile: i,
                sse_px: sse,
            });
        }
        if refine {
            stack.extend(t.children.iter().rev());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Aabb;
    use crate::tiles::tileset::TileNode;
    use glam::Vec3;

    fn node(error: f32, children: Vec<usize>, depth: usize, x: f32) -> TileNode {
        TileNode {
            bounds: Aabb {
                min: Vec3::new(x - 1.0, -1.0, -1.0),
                max: Vec3::new(x + 1.0, 1.0, 1.0),
            },
            error,
            content: None,
            children,
            depth,
            add: false,
        }
    }

    fn view(eye: Vec3) -> View {
        View {
            eye,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: std::f32::consts::FRAC_PI_4,
            width: 800,
            height: 600,
            light_dir: Vec3::Y,
        }
    }

    /// Far away the root alone; close, its children instead (REPLACE) or
    /// with it (ADD); behind the eye, nothing.
    #[test]
    fn far_draws_the_root_near_its_children() {
        let mut set = Tileset {
            tiles: vec![
                node(0.1, vec![1, 2], 0, 0.0),
                node(0.0, vec![], 1, -0.5),
                node(0.0, vec![], 1, 0.5),
            ],
        };
        let mut out = Vec::new();
        cut(&set, &view(Vec3::new(0.0, 0.0, 1000.0)), 16.0, &mut out);
        assert_eq!(out.iter().map(|d| d.tile).collect::<Vec<_>>(), [0]);
        // 0.1 · 724 px / d > 16 px for d < 4.5.
        cut(&set, &view(Vec3::new(0.0, 0.0, 4.0)), 16.0, &mut out);
        assert_eq!(out.iter().map(|d| d.tile).collect::<Vec<_>>(), [1, 2]);
        set.tiles[0].add = true;
        cut(&set, &view(Vec3::new(0.0, 0.0, 4.0)), 16.0, &mut out);
        assert_eq!(out.iter().map(|d| d.tile).collect::<Vec<_>>(), [0, 1, 2]);
        let mut away = view(Vec3::new(0.0, 0.0, 4.0));
        away.target = Vec3::new(0.0, 0.0, 10.0);
        cut(&set, &away, 16.0, &mut out);
        assert!(out.is_empty());
    }
}
