//! Shapes, transforms, the scene BVH and batched visibility queries.
//!
//! - [`Mesh`], [`Sphere`], [`Disk`], [`Rectangle`]: geometry components, placed by a [`Transform`].
//! - [`SceneBvh`]: one wide BVH (built by obvhs, 8 children per node: `wide.rs`) over every
//!   world-space triangle and analytic shape; see `bvh.rs` for the build / refit choices (their
//!   measured costs: docs/performance.md), `refit.rs` for updates.
//! - [`occluded`] and [`closest_hits`]: batched any-hit and closest-hit queries (rayon);
//!   `SceneBvh::closest_hits_packet` and `occluded_packet` answer 16 rays at once (`packets.rs`).
//! - [`offset_ray_origin`], [`SurfacePoint`]: robust shadow-ray endpoints with stated error bounds.
pub mod bvh;
pub mod mesh;
mod packets;
pub mod ray;
mod refit;
pub mod shapes;
pub mod transform;
mod triangle;
pub mod visibility;
mod wide;

pub use bvh::{BuildReport, GeometryId, GeometryInstance, GeometryRef, SceneBvh, UpdateKind};
pub use mesh::Mesh;
pub use packets::{HitSink, ray_columns};
pub use ray::{Ray, SHADOW_EPSILON, ShadowOffset, SurfacePoint, offset_ray_origin, triangle_surface_point};
pub use shapes::{Disk, PlacedShape, Rectangle, Shape, ShapeHit, Sphere};
pub use transform::{Placement, Transform};
pub use triangle::MAX_COORDINATE;
pub use visibility::{Hit, RAY_CHUNK, closest_hits, occluded};

use glam::Vec3;
use thiserror::Error;

/// Bad geometry input: what is wrong and where.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GeometryError {
    #[error("mesh vertex {index} has a non-finite position {value}")]
    NonFiniteVertex { index: usize, value: Vec3 },
    #[error("mesh {attribute} entry {index} is not finite")]
    NonFiniteAttribute { attribute: &'static str, index: usize },
    #[error("mesh has {count} indices, which is not a multiple of 3")]
    IndexCountNotTriangles { count: usize },
    #[error("mesh triangle {triangle} uses vertex {index}, but the mesh has only {vertex_count} vertices")]
    IndexOutOfRange { triangle: usize, index: u32, vertex_count: usize },
    #[error("mesh {attribute} has {len} entries; expected one per vertex ({expected})")]
    AttributeLength { attribute: &'static str, len: usize, expected: usize },
    #[error("invalid {} size: {shape:?} (sizes must be finite and positive, inner radius below radius)", shape.name())]
    InvalidShape { shape: Shape },
    #[error("a {} cannot be sheared (shear {shear}): only meshes follow a shearing transform", shape.name())]
    ShearedShape { shape: Shape, shear: Vec3 },
    #[error("a sphere needs a uniform scale, got {scale}")]
    NonUniformSphereScale { scale: Vec3 },
    #[error("transform is not finite or not invertible: {transform:?}")]
    InvalidTransform { transform: Transform },
    #[error("instance {instance} (entity {entity_index}): {source}")]
    Instance {
        instance: u32,
        entity_index: u32,
        #[source]
        source: Box<GeometryError>,
    },
    #[error("instance {instance} is out of range: the BVH was built from {count} instances")]
    UnknownInstance { instance: u32, count: usize },
    #[error("instance {instance} was left out of the BVH or would be now; refit cannot add or remove it, rebuild")]
    RefitNeedsRebuild { instance: u32 },
}
