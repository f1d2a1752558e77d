//! Meshes: triangle primitives with positions, normals and UV sets 0 and 1 (textures, lightmaps); strips and fans become lists, bad triangles
//! are dropped with a warning.

use ::gltf::json::mesh::{Mode, Semantic};
use ::gltf::json::validation::Checked;
use glam::{Vec2, Vec3};

use super::accessor::{read_indices, read_vectors};
use super::{Doc, GltfError, MeshData, PrimitiveData, Warnings};

/// Reads every mesh of the file (indexed as in the file). Accessor errors are fatal; everything else is a
/// warning with the primitive or its bad triangles dropped.
pub(super) fn read_meshes(doc: &Doc, warnings: &mut Warnings) -> Result<Vec<MeshData>, GltfError> {
    let mut meshes = Vec::with_capacity(doc.root.meshes.len());
    for (m, mesh) in doc.root.meshes.iter().enumerate() {
        if mesh.primitives.iter().any(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty())) {
            warnings.push(&format!("/meshes/{m}"), "morph targets ignored (the base shape is used)");
        }
        let mut primitives = Vec::with_capacity(mesh.primitives.len());
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let pointer = format!("/meshes/{m}/primitives/{p}");
            if let Some(primitive) = read_primitive(doc, primitive, &pointer, warnings)? {
                primitives.push(primitive);
            }
        }
        meshes.push(MeshData { name: mesh.name.clone(), primitives });
    }
    Ok(meshes)
}

fn read_primitive(
    doc: &Doc,
    primitive: &::gltf::json::mesh::Primitive,
    pointer: &str,
    warnings: &mut Warnings,
) -> Result<Option<PrimitiveData>, GltfError> {
    if doc.raw(&format!("{pointer}/extensions/KHR_draco_mesh_compression")).is_some() {
        warnings.push(pointer, "Draco-compressed primitive skipped (KHR_draco_mesh_compression is not supported)");
        return Ok(None);
    }
    let mode = match primitive.mode {
        Checked::Valid(mode @ (Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)) => mode,
        Checked::Valid(other) => {
            warnings.push(pointer, format!("mode {other:?} is not triangles; primitive skipped"));
            return Ok(None);
        }
        Checked::Invalid => {
            warnings.push(pointer, "invalid mode; primitive skipped");
            return Ok(None);
        }
    };
    let attribute = |semantic: Semantic| primitive.attributes.get(&Checked::Valid(semantic)).map(|i| i.value());
    let Some(position_accessor) = attribute(Semantic::Positions) else {
        warnings.push(pointer, "no POSITION attribute; primitive skipped");
        return Ok(None);
    };
    let mut positions: Vec<Vec3> =
        read_vectors::<3>(doc, position_accessor, "POSITION")?.into_iter().map(Vec3::from_array).collect();
    let n = positions.len();
    if n == 0 {
        warnings.push(pointer, "no vertices; primitive skipped");
        return Ok(None);
    }
    if n > u32::MAX as usize {
        return Err(doc.invalid(pointer, format!("{n} vertices (at most 2^32 - 1)")));
    }

    let mut normals = match attribute(Semantic::Normals) {
        Some(a) => Some(read_vectors::<3>(doc, a, "NORMAL")?.into_iter().map(Vec3::from_array).collect::<Vec<_>>()),
        None => None,
    };
    if normals.as_ref().is_some_and(|v| v.len() != n) {
        warnings.push(pointer, format!("NORMAL count differs from POSITION count {n}; normals dropped"));
        normals = None;
    }
    if normals.as_ref().is_some_and(|v| v.iter().any(|v| !v.is_finite())) {
        warnings.push(pointer, "NaN or infinite normals; normals dropped");
        normals = None;
    }

    let uvs = read_uv_set(doc, attribute(Semantic::TexCoords(0)), 0, n, pointer, warnings)?;
    let uvs1 = read_uv_set(doc, attribute(Semantic::TexCoords(1)), 1, n, pointer, warnings)?;

    let vertex_order = match primitive.indices {
        Some(a) => read_indices(doc, a.value())?,
        None => (0..n as u32).collect(),
    };
    let mut indices = match mode {
        Mode::TriangleStrip => strip_to_list(&vertex_order),
        Mode::TriangleFan => fan_to_list(&vertex_order),
        _ => {
            let whole = vertex_order.len() / 3 * 3;
            if whole != vertex_order.len() {
                warnings
                    .push(pointer, format!("{} indices is not a multiple of 3; the rest dropped", vertex_order.len()));
            }
            vertex_order[..whole].to_vec()
        }
    };
    drop_bad_triangles(&mut indices, &positions, pointer, warnings);
    if indices.is_empty() {
        warnings.push(pointer, "no triangles; primitive skipped");
        return Ok(None);
    }
    // Non-finite vertices are now unused; move them onto a kept vertex so that every position is finite (a mesh
    // with one NaN vertex is refused whole downstream) without stretching the mesh's bounds.
    let anchor = positions[indices[0] as usize];
    positions.iter_mut().filter(|p| !p.is_finite()).for_each(|p| *p = anchor);

    let material = primitive.material.map(|m| m.value()).filter(|&m| {
        let exists = m < doc.root.materials.len();
        if !exists {
            warnings
                .push(&format!("{pointer}/material"), format!("material {m} does not exist; default material used"));
        }
        exists
    });
    Ok(Some(PrimitiveData { positions, normals, uvs, uvs1, indices, material }))
}

/// Reads TEXCOORD_`set` (accessor `accessor`, if any) of a primitive with `n` vertices: a count other than `n`
/// drops the set with a warning, and non-finite values become (0, 0) with a warning.
fn read_uv_set(
    doc: &Doc,
    accessor: Option<usize>,
    set: u32,
    n: usize,
    pointer: &str,
    warnings: &mut Warnings,
) -> Result<Option<Vec<Vec2>>, GltfError> {
    let Some(a) = accessor else { return Ok(None) };
    let name = format!("TEXCOORD_{set}");
    let mut uvs: Vec<Vec2> = read_vectors::<2>(doc, a, &name)?.into_iter().map(Vec2::from_array).collect();
    if uvs.len() != n {
        warnings.push(pointer, format!("{name} count differs from POSITION count {n}; uvs dropped"));
        return Ok(None);
    }
    let bad = uvs.iter().filter(|uv| !uv.is_finite()).count();
    if bad > 0 {
        warnings.push(pointer, format!("{bad} NaN or infinite {name} value(s) set to (0, 0)"));
        uvs.iter_mut().filter(|uv| !uv.is_finite()).for_each(|uv| *uv = Vec2::ZERO);
    }
    Ok(Some(uvs))
}

/// Drops triangles with an index out of range or a non-finite vertex, with one warning per cause.
fn drop_bad_triangles(indices: &mut Vec<u32>, positions: &[Vec3], pointer: &str, warnings: &mut Warnings) {
    let n = positions.len();
    let (mut out_of_range, mut non_finite) = (0usize, 0usize);
    let mut kept = Vec::with_capacity(indices.len());
    for tri in indices.chunks_exact(3) {
        if tri.iter().any(|&i| i as usize >= n) {
            out_of_range += 1;
        } else if tri.iter().any(|&i| !positions[i as usize].is_finite()) {
            non_finite += 1;
        } else {
            kept.extend_from_slice(tri);
        }
    }
    if out_of_range > 0 {
        warnings.push(pointer, format!("{out_of_range} triangle(s) with vertex indices >= {n} dropped"));
    }
    if non_finite > 0 {
        warnings.push(pointer, format!("{non_finite} triangle(s) with NaN or infinite positions dropped"));
    }
    *indices = kept;
}

/// Triangle strip to list, keeping the winding: triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}) (glTF 2.0 spec,
/// section 3.7.2.1 "Topology Types").
fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let triangles = v.len().saturating_sub(2);
    (0..triangles).flat_map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]).collect()
}

/// Triangle fan to list: triangle i is (v_{i+1}, v_{i+2}, v_0) (glTF 2.0 spec, section 3.7.2.1).
fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let triangles = v.len().saturating_sub(2);
    (0..triangles).flat_map(|i| [v[i + 1], v[i + 2], v[0]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_winding() {
        assert_eq!(strip_to_list(&[0, 1, 2, 3, 4]), vec![0, 1, 2, 1, 3, 2, 2, 3, 4]);
        assert_eq!(fan_to_list(&[0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
        assert!(strip_to_list(&[0, 1]).is_empty());
        assert!(fan_to_list(&[]).is_empty());
    }
}
