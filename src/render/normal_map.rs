//! Normal textures: a batch's shading normals replaced by the ones its materials' maps give,
//! before the light system sees the batch, so that light choice, Sample_Li's cosines, MIS and the
//! BSDF all use them. The tangent frame is the triangle's dp/du, dp/dv (as pbrt-v4 shades
//! triangles), so only meshes with uvs are mapped; glTF TANGENT attributes are not read.

use glam::Vec2;
use rayon::prelude::*;

use super::bsdf::bent_shading_normal;
use super::camera_pass::CameraColumns;
use super::shade::Materials;
use crate::geometry::{RAY_CHUNK, SceneBvh};
use crate::shading::ShadingBatch;

/// Replaces the shading normal of every slot of `batch` whose material has a normal texture.
/// A mapped normal that would face away from the slot's geometric normal is not used; one the
/// view would see from below is bent as the camera pass bends smooth normals.
pub(super) fn apply_normal_maps(
    batch: &mut ShadingBatch,
    columns: &CameraColumns,
    bvh: &SceneBvh,
    materials: &Materials,
) {
    if !materials.any_normal_map {
        return;
    }
    let ShadingBatch { shading_normal, normal, geometry, .. } = batch;
    shading_normal.par_iter_mut().enumerate().with_min_len(RAY_CHUNK).for_each(|(i, ns)| {
        if columns.escaped(i) {
            return;
        }
        let Some(material) = materials.materials.get(columns.material[i] as usize) else { return };
        if material.normal_texture.is_none() {
            return;
        }
        let Some((dpdu, dpdv)) = bvh.uv_derivatives(columns.instance[i], geometry[i].primitive) else { return };
        // The camera pass turned the normals toward the viewer; the map is in the front's frame.
        let flip = if columns.flipped[i] { -1.0 } else { 1.0 };
        let uv = Vec2::new(columns.uv[0][i], columns.uv[1][i]);
        if let Some(mapped) = material.mapped_normal(uv, *ns * flip, dpdu, dpdv) {
            let mapped = mapped * flip;
            if mapped.dot(normal[i]) > 0.0 {
                *ns = bent_shading_normal(mapped, normal[i], -columns.dir(i));
            }
        }
    });
}
