//! Distance measurement: a BVH over triangles or spheres, exact point-to-triangle
//! distance, and the sampled two-sided Hausdorff distance that every method's
//! guaranteed error bound is checked against; the UV error of a LOD; how
//! different two renders look ([`visual`]).

pub mod bvh;
pub mod facets;
pub mod hausdorff;
pub mod ray;
pub mod triangle;
pub mod uv;
pub mod visual;
pub mod winding;

pub use bvh::{Bvh, MeshDistance, SphereSetDistance};
pub use hausdorff::{
    HausdorffReport, SamplingOptions, hausdorff_mesh_mesh, hausdorff_mesh_spheres, sample_surface,
};
pub use ray::{Hit, RayCaster};
pub use triangle::{barycentric, closest_point_on_segment, closest_point_on_triangle};
pub use uv::{UV_ERROR_THRESHOLD, UvError, uv_error};
pub use winding::WindingNumber;
