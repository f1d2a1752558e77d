//! What to bake: the placed glTF meshes with TEXCOORD_1, one lightmap each (a mesh's primitives
//! share its uv1 atlas, as Bevy's lightmaps do), with names unique in the bake.

use std::collections::{HashMap, HashSet};

use bevy_ecs::world::World;
use glam::Vec3;

use super::texels::Surface;
use super::{BakeError, BakeReport};
use crate::geometry::Mesh;
use crate::render::material::Material;
use crate::scene::spawn::SpawnedPrimitive;

/// One lightmap to bake.
pub(super) struct Target {
    pub(super) name: String,
    pub(super) mesh_name: Option<String>,
    pub(super) node_name: Option<String>,
    pub(super) surfaces: Vec<Surface>,
}

/// The lightmaps `primitives` call for (one per placed mesh with TEXCOORD_1, in the file's order),
/// and a report of the meshes skipped.
pub(super) fn gather(world: &World, primitives: &[SpawnedPrimitive]) -> Result<(Vec<Target>, BakeReport), BakeError> {
    let mut report = BakeReport::default();
    // A placed mesh's primitives were spawned one after another.
    let mut groups: Vec<Vec<&SpawnedPrimitive>> = Vec::new();
    for p in primitives {
        match groups.last_mut() {
            Some(g) if (g[0].mesh, g[0].instance) == (p.mesh, p.instance) => g.push(p),
            _ => groups.push(vec![p]),
        }
    }
    let mut placements: HashMap<usize, usize> = HashMap::new();
    for g in groups.iter().filter(|g| g.iter().any(|p| p.uvs1.is_some())) {
        *placements.entry(g[0].mesh).or_default() += 1;
    }
    let (mut targets, mut used) = (Vec::new(), HashSet::new());
    for group in &groups {
        let p0 = group[0];
        let label = p0.mesh_name.clone().unwrap_or_else(|| format!("mesh{}", p0.mesh));
        let node = p0.node_name.clone().unwrap_or_else(|| format!("{}", p0.instance));
        let mut surfaces = Vec::new();
        for p in group {
            let (Some(uvs1), Some(mesh)) = (&p.uvs1, world.get::<Mesh>(p.entity)) else { continue };
            if uvs1.len() != mesh.positions().len() {
                report.warnings.push(format!(
                    "mesh {label} primitive {}: TEXCOORD_1 count differs from the mesh's vertices; not baked",
                    p.primitive
                ));
                continue;
            }
            let albedo = world.get::<Material>(p.entity).map_or(Vec3::ONE, diffuse_albedo);
            let entity_index = p.entity.index_u32();
            surfaces.push(Surface { mesh: mesh.clone(), uvs1: uvs1.clone(), entity_index, albedo });
        }
        if surfaces.is_empty() {
            report.skipped.push(format!("mesh {label} (node {node}): no TEXCOORD_1 (lightmap uvs); skipped"));
            continue;
        }
        if surfaces.len() < group.len() {
            let missing = group.len() - surfaces.len();
            report.warnings.push(format!(
                "mesh {label}: {missing} of its {} primitives have no TEXCOORD_1; they are not baked",
                group.len()
            ));
        }
        let mut name = file_safe(&label);
        if placements[&p0.mesh] > 1 {
            name = format!("{name}.{}", file_safe(&node));
        }
        while !used.insert(name.clone()) {
            name = format!("{name}.{}", p0.instance);
        }
        targets.push(Target { name, mesh_name: p0.mesh_name.clone(), node_name: p0.node_name.clone(), surfaces });
    }
    if targets.is_empty() {
        let why = match groups.len() {
            0 => "the scene has no glTF meshes".to_string(),
            n => format!("none of the scene's {n} placed meshes has TEXCOORD_1 (the lightmap uvs)"),
        };
        return Err(BakeError::NothingToBake(why));
    }
    Ok((targets, report))
}

/// `name` with every character but ASCII letters, digits, `.`, `_` and `-` replaced by `_`, so it
/// names a file on any system.
fn file_safe(name: &str) -> String {
    let safe: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') { c } else { '_' }).collect();
    if safe.is_empty() || safe.starts_with('.') { format!("mesh{safe}") } else { safe }
}

/// The colour an engine multiplies a lightmap by on `m`: its base colour (times its texture's mean)
/// on the share that is not metal, as Bevy's `diffuse_color`.
fn diffuse_albedo(m: &Material) -> Vec3 {
    let texture = m
        .base_color_texture
        .as_ref()
        .map_or(Vec3::ONE, |t| t.pixels.iter().fold(Vec3::ZERO, |sum, p| sum + *p) / t.pixels.len().max(1) as f32);
    m.base_color * texture * (1.0 - m.metallic)
}

#[cfg(test)]
mod tests {
    #[test]
    fn file_names_are_safe() {
        assert_eq!(super::file_safe("cornell_box"), "cornell_box");
        assert_eq!(super::file_safe("a/b c:d"), "a_b_c_d");
        assert_eq!(super::file_safe(".."), "mesh..");
        assert_eq!(super::file_safe(""), "mesh");
    }
}
