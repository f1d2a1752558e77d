//! Shapes, transforms, the scene BVH and batched visibility queries.
//!
//! - [`Mesh`], [`Sphere`], [`Disk`], [`Rectangle`]: geometry components, placed by a [`Transform`].
//! - [`SceneBvh`]: one wide BVH (built by obvhs, 8 children per node: `wide.rs`) over every
//!   world-space triangle and analytic shape; see `bvh.rs` for the build / refit choices (their
//!   measured costs: docs/performance.md), `refit.rs` for updates.
//! - [`occluded`] and [`closest_hits`]: batched any-hit and closest-hit queries (rayon);
//!   `SceneBvh::closest_hits_packet` (hits as [`HitLanes`] columns, `hits.rs`) and `occluded_packet`
//!   answer 16 rays at once (`packets.rs`).
//! - [`ClosedSurfaces`]: which triangles bound a solid (closed, consistently wound; `closed.rs`).
//! - [`offset_ray_origin`], [`SurfacePoint`]: robust shadow-ray endpoints with stated error bounds.
pub mod bvh;
mod closed;
mod hits;
pub mod mesh;
mod packets;
pub mod ray;
pub mod ray_stats;
mod refit;
pub mod shapes;
pub mod transform;
mod triangle;
pub mod visibility;
mod wide;

pub use bvh::{BuildReport, GeometryId, GeometryInstance, GeometryRef, SceneBvh, UpdateKind};
pub use closed::{CONTACT, ClosedSurfaces, closed_triangles};
pub use hits::HitLanes;
pub(crate) use hits::mesh_point;
pub use mesh::Mesh;
pub use packets::{closest_hits_in_packets, ray_columns};
pub use ray::{Ray, SHADOW_EPSILON, ShadowOffset, SurfacePoint, offset_ray_origin, triangle_surface_point};
pub use shapes::{Disk, PlacedShape, Rectangle, Shape, ShapeHit, Sphere};
pub use transform::{Placement, Transform};
pub use triangle::MAX_COORDINATE;
pub use visibility::{Hit, HitRef, RAY_CHUNK, closest_hits, occluded};

use glam::Vec3;
use thiserror::Error;

/// Bad geometry input: what is wrong and where.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GeometryError {
    /// [`Mesh::new`] was given a vertex position with a NaN or infinite coordinate.
    #[error("mesh vertex {index} has a non-finite position {value}")]
    NonFiniteVertex {
        /// Index of the vertex.
        index: usize,
        /// Its position.
        value: Vec3,
    },
    /// A normal or uv handed to [`Mesh::with_normals`] or [`Mesh::with_uvs`] is not finite.
    #[error("mesh {attribute} entry {index} is not finite")]
    NonFiniteAttribute {
        /// `"normals"` or `"uvs"`.
        attribute: &'static str,
        /// Index of the entry (the vertex).
        index: usize,
    },
    /// [`Mesh::new`] was given an index list whose length is not a multiple of 3.
    #[error("mesh has {count} indices, which is not a multiple of 3")]
    IndexCountNotTriangles {
        /// Length of the index list.
        count: usize,
    },
    /// A triangle refers to a vertex the mesh does not have.
    #[error("mesh triangle {triangle} uses vertex {index}, but the mesh has only {vertex_count} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The out-of-range vertex index.
        index: u32,
        /// Number of vertex positions.
        vertex_count: usize,
    },
    /// Normals or uvs were given with a count other than one per vertex position.
    #[error("mesh {attribute} has {len} entries; expected one per vertex ({expected})")]
    AttributeLength {
        /// `"normals"` or `"uvs"`.
        attribute: &'static str,
        /// Number of entries given.
        len: usize,
        /// Number of vertex positions.
        expected: usize,
    },
    /// A shape size is not finite and positive, or a disk's inner radius is not below its radius.
    #[error("invalid {} size: {shape:?} (sizes must be finite and positive, inner radius below radius)", shape.name())]
    InvalidShape {
        /// The rejected shape.
        shape: Shape,
    },
    /// An analytic shape was placed by a transform with shear; only meshes follow shear.
    #[error("a {} cannot be sheared (shear {shear}): only meshes follow a shearing transform", shape.name())]
    ShearedShape {
        /// The shape.
        shape: Shape,
        /// The transform's shear (see [`Transform::shear`]).
        shear: Vec3,
    },
    /// A sphere was placed with a non-uniform scale (it would be an ellipsoid).
    #[error("a sphere needs a uniform scale, got {scale}")]
    NonUniformSphereScale {
        /// The transform's scale.
        scale: Vec3,
    },
    /// A transform is not finite or not invertible (e.g. a zero scale or a zero rotation), or it
    /// puts a shape's bounds out of f32 range.
    #[error("transform is not finite or not invertible: {transform:?}")]
    InvalidTransform {
        /// The rejected transform.
        transform: Transform,
    },
    /// An instance the BVH build left out (listed in [`BuildReport::skipped_instances`]), and why.
    #[error("instance {instance} (entity {entity_index}): {source}")]
    Instance {
        /// Index of the instance in the list given to [`SceneBvh::build`].
        instance: u32,
        /// `Entity::index()` of its owner.
        entity_index: u32,
        /// What is wrong with it.
        #[source]
        source: Box<GeometryError>,
    },
    /// An update named an instance index the BVH was not built with; nothing was changed.
    #[error("instance {instance} is out of range: the BVH was built from {count} instances")]
    UnknownInstance {
        /// The unknown instance index.
        instance: u32,
        /// Number of instances the BVH was built from.
        count: usize,
    },
    /// [`SceneBvh::refit`] cannot move this instance: its new transform would add it to the tree or
    /// drop it (valid now but left out at the build, or the reverse). Nothing was changed; rebuild.
    #[error("instance {instance} was left out of the BVH or would be now; refit cannot add or remove it, rebuild")]
    RefitNeedsRebuild {
        /// Index of the instance.
        instance: u32,
    },
}
