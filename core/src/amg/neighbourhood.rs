//! §2.1: the neighbourhood N of every point — its k_min nearest neighbours,
//! grown to the whole ball B_ε(x) when the k_min-th one is closer than ε.

use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Neighbour lists (without the point itself), nearest first, and each
/// neighbourhood's radius (the ε the classifier divides by, eq. 3).
#[derive(Debug, Clone)]
pub struct Neighbourhoods {
    pub lists: Vec<Vec<u32>>,
    pub radii: Vec<f32>,
}

/// The k-d tree of a point set, kept for the later nearest-point look-ups.
pub fn kd_tree(points: &[Vec3]) -> ImmutableKdTree<f32, 3> {
    let arrays: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    ImmutableKdTree::new_from_slice(&arrays).expect("a non-empty set of finite points")
}

/// §2.1: k_min nearest neighbours, plus every other point in B_ε(x) when the
/// k_min-th neighbour lies inside it (ε = 0 keeps the plain k-NN).
pub fn neighbourhoods(points: &[Vec3], k_min: usize, epsilon: f32) -> Neighbourhoods {
    let tree = kd_tree(points);
    let k = NonZero::new((k_min + 1).min(points.len())).expect("at least one point");
    let (lists, radii) = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let q = p.to_array();
            let mut near = tree
                .query(&q)
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .execute();
            let kth = near.last().map_or(0.0, |n| n.distance);
            if epsilon > 0.0 && kth < epsilon * epsilon {
                near = tree
                    .query(&q)
                    .within::<SquaredEuclidean<f32>>(epsilon * epsilon)
                    .execute();
            }
            let radius = near.iter().fold(0f32, |r, n| r.max(n.distance)).sqrt();
            let list: Vec<u32> = near
                .iter()
                .map(|n| n.item)
                .filter(|&j| j as usize != i)
                .collect();
            (list, radius.max(epsilon))
        })
        .unzip();
    Neighbourhoods { lists, radii }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_neighbours_are_the_nearest_and_the_ball_grows_them() {
        let pts: Vec<Vec3> = (0..400)
            .map(|i| Vec3::new((i % 20) as f32, (i / 20) as f32, 0.0))
            .collect();
        let n = neighbourhoods(&pts, 4, 0.0);
        // An interior grid point's 4 nearest are its 4 axis neighbours at distance 1.
        let i = 10 * 20 + 10;
        let mut l = n.lists[i].clone();
        l.sort();
        assert_eq!(
            l,
            vec![i as u32 - 20, i as u32 - 1, i as u32 + 1, i as u32 + 20]
        );
        assert!((n.radii[i] - 1.0).abs() < 1e-6);
        // ε = 2.1 takes the whole ball: 12 lattice points within distance 2.1 besides itself.
        let n = neighbourhoods(&pts, 4, 2.1);
        assert_eq!(n.lists[i].len(), 12);
        assert!(!n.lists[i].contains(&(i as u32)));
    }
}
