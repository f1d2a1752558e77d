//! Shapes, transforms, the scene BVH and batched visibility queries.
pub mod transform;

pub use transform::Transform;
