//! Turning an imported glTF scene into entities: meshes (baked to world space, the winding reversed
//! under mirroring node transforms, as glTF asks) with materials, emissive surfaces as area lights,
//! KHR_lights_punctual / EXT_lights_ies lights, and cameras.
//!
//! Light units are glTF's: candela for point and spot lights, lux for directional ones, and for
//! EXT_lights_ies lights a multiplier on the profile's candela values. A light's colour is its
//! chromaticity (an RGB-derived spectrum); its luminous amount is the intensity (or multiplier)
//! times the colour's luminance, as an RGB renderer multiplying colour by intensity would show, so
//! a black light of any kind emits nothing.
//! `range` is ignored: kelvin keeps the inverse-square law everywhere (glTF allows a renderer to
//! treat range as a culling hint).

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec2, Vec3};

use super::animate::{GltfAnimations, GltfNode};
use super::gltf::{GltfScene, IesSource, LightKind, MaterialData};
use super::ies::IesProfile;
use crate::geometry::{Mesh, Transform};
use crate::light::{Amount, DistantLight, GoniometricLight, PointLight, SpotLight};
use crate::render::camera::Camera;
use crate::render::material::Material;
use crate::spectrum::Spectrum;

/// What was spawned, and what was skipped with why.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpawnReport {
    /// Mesh entities spawned, one per glTF mesh primitive and instance.
    pub meshes: usize,
    /// Triangles over all spawned meshes.
    pub triangles: usize,
    /// Spawned meshes that are also area lights (an emissive material).
    pub emissive_meshes: usize,
    /// Punctual and IES lights spawned (emissive meshes not counted).
    pub lights: usize,
    /// Cameras spawned.
    pub cameras: usize,
    /// The file's index in the world's [`GltfAnimations`] (what `animate::pose_gltf` takes).
    pub file: usize,
    /// Its animations.
    pub animations: usize,
    /// The loader's warnings, then what spawning skipped and why.
    pub warnings: Vec<String>,
    /// Every spawned mesh entity, in the order spawned, with where it came from in the file.
    pub primitives: Vec<SpawnedPrimitive>,
    /// The IES profile files read while spawning, each with the SHA-256 of the bytes parsed.
    pub inputs: Vec<crate::provenance::InputFile>,
}

/// A mesh entity spawned from a glTF mesh primitive, with what a lightmap baker needs that the
/// world's `Mesh` does not keep: the file's names and the primitive's TEXCOORD_1. The entity's
/// `Mesh` has the primitive's vertices in the same order, and its triangles in the same order.
#[derive(Clone, Debug, PartialEq)]
pub struct SpawnedPrimitive {
    /// The entity with the primitive's `Mesh` (world space) and `Material`.
    pub entity: Entity,
    /// Index of the glTF mesh in [`GltfScene::meshes`].
    pub mesh: usize,
    /// The glTF mesh's name, if the file gives one.
    pub mesh_name: Option<String>,
    /// Index of the placement in [`GltfScene::instances`].
    pub instance: usize,
    /// The name of the node that places it, if the file gives one.
    pub node_name: Option<String>,
    /// Index of the primitive in its mesh's (read) primitives.
    pub primitive: usize,
    /// The primitive's TEXCOORD_1, one per vertex.
    pub uvs1: Option<Vec<Vec2>>,
}

/// Rec. 709 luminance of linear RGB.
fn luminance(c: Vec3) -> f32 {
    c.dot(crate::scene::image::LUMINANCE_WEIGHTS)
}

/// A colour as an RGB-derived spectrum (white (1,1,1) is D65) and its luminance.
fn colour_spectrum(c: Vec3) -> (Spectrum, f32) {
    let y = luminance(c);
    if y > 0.0 { (Spectrum::Rgb { rgb: (c / y).as_dvec3().to_array() }, y) } else { (Spectrum::d65(), 0.0) }
}

fn material_of(m: &MaterialData, scene: &GltfScene) -> Material {
    let tex = |i: Option<usize>| i.and_then(|i| scene.textures.get(i).cloned());
    Material {
        base_color: m.base_color.truncate(),
        base_color_texture: tex(m.base_color_texture),
        metallic: m.metallic,
        roughness: m.roughness,
        metallic_roughness_texture: tex(m.metallic_roughness_texture),
        normal_texture: tex(m.normal_texture),
        normal_scale: m.normal_scale,
        specular: m.specular_factor,
        ior: m.ior,
        double_sided: m.double_sided,
    }
}

/// Spawns everything in `scene` into `world`. Each entity placed by a node carries its
/// [`GltfNode`], and the file's node tree and animations are added to the world's
/// [`GltfAnimations`], so that `animate::pose_gltf` can move them.
pub fn spawn_gltf(world: &mut World, scene: &GltfScene) -> SpawnReport {
    let mut report = SpawnReport { warnings: scene.warnings.clone(), ..Default::default() };
    {
        let mut animations = world.get_resource_or_init::<GltfAnimations>();
        (report.file, report.animations) = (animations.files.len(), scene.animations.clips.len());
        animations.files.push(scene.animations.clone());
    }
    let file = report.file;
    let at_node = |node: Option<usize>, rest_inverse| node.map(|node| GltfNode { file, node, rest_inverse });
    let materials: Vec<Material> = scene.materials.iter().map(|m| material_of(m, scene)).collect();
    // Each material's area light, made once (its texture checked once, with one warning).
    let emitters: Vec<Option<crate::light::AreaLight>> =
        scene.materials.iter().enumerate().map(|(i, m)| emissive_light(i, m, scene, &mut report.warnings)).collect();
    for (i, inst) in scene.instances.iter().enumerate() {
        let Some(mesh) = scene.meshes.get(inst.mesh) else { continue };
        // Normals take the inverse transpose (right under mirrors too). A mirroring transform (negative
        // determinant) reverses the winding (glTF 2.0 spec, section 3.7.4), so the world-space triangles
        // swap two corners to keep their front face, which one-sided emitters emit from.
        let normal_matrix = inst.world.matrix3.inverse().transpose();
        let mirrors = inst.world.matrix3.determinant() < 0.0;
        let inverse = inst.world.inverse();
        let node = at_node(inst.node, inverse.is_finite().then_some(inverse));
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh {} primitive {p}", mesh.name.as_deref().unwrap_or("?"));
            let positions: Vec<Vec3> = prim.positions.iter().map(|&v| inst.world.transform_point3(v)).collect();
            let mut indices = prim.indices.clone();
            if mirrors {
                indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
            }
            let mut built = Mesh::new(positions, indices);
            if let (Ok(m), Some(n)) = (&built, &prim.normals) {
                let normals = n.iter().map(|&v| (normal_matrix * v).normalize_or_zero()).collect();
                built = m.clone().with_normals(normals);
            }
            if let (Ok(m), Some(uv)) = (&built, &prim.uvs) {
                built = m.clone().with_uvs(uv.clone());
            }
            let mesh_component = match built {
                Ok(m) => m,
                Err(e) => {
                    report.warnings.push(format!("{what} skipped: {e}"));
                    continue;
                }
            };
            let material = prim.material.and_then(|i| materials.get(i).cloned()).unwrap_or_default();
            report.meshes += 1;
            report.triangles += mesh_component.triangle_count();
            let mut entity = world.spawn((mesh_component, Transform::IDENTITY, material));
            if let Some(node) = node {
                entity.insert(node);
            }
            report.primitives.push(SpawnedPrimitive {
                entity: entity.id(),
                mesh: inst.mesh,
                mesh_name: mesh.name.clone(),
                instance: i,
                node_name: inst.node_name.clone(),
                primitive: p,
                uvs1: prim.uvs1.clone(),
            });
            if let Some(area) = prim.material.and_then(|i| emitters.get(i).cloned().flatten()) {
                entity.insert(area);
                report.emissive_meshes += 1;
            }
        }
    }
    for light in &scene.lights {
        let transform = Transform::from_affine(light.world);
        let (spectrum, y) = colour_spectrum(light.color);
        let luminous = light.intensity * y;
        let mut e = world.spawn_empty();
        if let Some(node) = at_node(light.node, Some(Affine3A::IDENTITY)) {
            e.insert(node);
        }
        match light.kind {
            LightKind::Point => {
                e.insert((PointLight { amount: Amount::Candela(luminous), spectrum, ..Default::default() }, transform));
            }
            LightKind::Spot { inner_cone_angle, outer_cone_angle } => {
                let spot = SpotLight {
                    amount: Amount::Candela(luminous),
                    spectrum,
                    inner_angle: inner_cone_angle,
                    outer_angle: outer_cone_angle,
                    ..Default::default()
                };
                e.insert((spot, transform));
            }
            LightKind::Directional => {
                e.insert((DistantLight { amount: Amount::Lux(luminous), spectrum, ..Default::default() }, transform));
            }
            LightKind::Ies => match load_ies(light.ies.as_ref(), &mut report.inputs) {
                Ok(profile) => {
                    // The multiplier scales the profile's candela values; the colour weighs them by its
                    // luminance, as for the other kinds (a black colour gives no light).
                    let mut g = GoniometricLight::from_ies(Arc::new(profile));
                    g.amount = Amount::Candela(luminous);
                    g.spectrum = spectrum;
                    e.insert((g, transform));
                }
                Err(msg) => {
                    report.warnings.push(format!("IES light {} skipped: {msg}", light.name.as_deref().unwrap_or("?")));
                    e.despawn();
                    continue;
                }
            },
        }
        report.lights += 1;
    }
    for cam in &scene.cameras {
        let mut e = world.spawn((Camera { yfov: cam.yfov }, Transform::from_affine(cam.world)));
        if let Some(node) = at_node(cam.node, Some(Affine3A::IDENTITY)) {
            e.insert(node);
        }
        report.cameras += 1;
    }
    if let Some(sky) = &scene.sky {
        world.spawn((sky.clone(), Transform::IDENTITY));
        report.lights += 1;
    }
    report
}

/// The profile of an IES light; a file's bytes are recorded in `inputs` as read.
fn load_ies(source: Option<&IesSource>, inputs: &mut Vec<crate::provenance::InputFile>) -> Result<IesProfile, String> {
    match source {
        Some(IesSource::File(path)) => {
            let what = path.display().to_string();
            let bytes = std::fs::read(path).map_err(|e| format!("{what}: {e}"))?;
            inputs.push(crate::provenance::InputFile::read(path, &bytes));
            // As IesProfile::from_file reads it: bytes that are not UTF-8 (Latin-1 keywords) are replaced.
            IesProfile::parse(&String::from_utf8_lossy(&bytes), &what).map_err(|e| e.to_string())
        }
        Some(IesSource::Embedded { bytes, what }) => {
            let text = std::str::from_utf8(bytes).map_err(|_| format!("{what}: not UTF-8 text"))?;
            IesProfile::parse(text, what).map_err(|e| e.to_string())
        }
        None => Err("no profile".into()),
    }
}

/// The area light emissive material `index` makes, if any. An emissive texture an area light
/// cannot use (a texel NaN, infinite or negative) is dropped, and the surface emits its factor
/// uniformly, with a warning naming the material, the texture and how many texels are bad.
fn emissive_light(
    index: usize,
    m: &MaterialData,
    scene: &GltfScene,
    warnings: &mut Vec<String>,
) -> Option<crate::light::AreaLight> {
    let y = luminance(m.emissive);
    if y.is_nan() || y <= 0.0 {
        return None;
    }
    let (spectrum, _) = colour_spectrum(m.emissive);
    let mut texture = m.emissive_texture.and_then(|i| scene.textures.get(i).map(|t| (i, t.clone())));
    if let Some((t, image)) = &texture {
        let material = match &m.name {
            Some(name) => format!("material {index} {name:?}"),
            None => format!("material {index}"),
        };
        let not_finite = image.pixels.iter().filter(|p| !p.is_finite()).count();
        let negative = image.pixels.iter().filter(|p| p.is_finite() && p.min_element() < 0.0).count();
        if not_finite + negative > 0 {
            warnings.push(format!(
                "{material}: emissiveTexture (texture {t}) has {not_finite} NaN or infinite and {negative} negative \
                 texel(s) of {}; the texture is dropped and the surface emits its emissiveFactor uniformly",
                image.pixels.len()
            ));
            texture = None;
        } else if image.width * image.height != image.pixels.len() || image.pixels.is_empty() {
            let (w, h, n) = (image.width, image.height, image.pixels.len());
            warnings.push(format!("{material}: emissiveTexture (texture {t}) has {n} texel(s) for {w} x {h}; dropped"));
            texture = None;
        }
    }
    Some(crate::light::AreaLight::emissive(Amount::Nits(y), spectrum, texture.map(|(_, t)| t), m.double_sided))
}

#[cfg(test)]
mod tests {
    use glam::Quat;

    use super::*;
    use crate::scene::gltf::{MeshData, MeshInstance, PrimitiveData};

    /// A triangle with NORMAL data matching its winding (+Z), placed by `world`.
    fn one_triangle(world: Affine3A) -> GltfScene {
        let primitive = PrimitiveData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: Some(vec![Vec3::Z; 3]),
            uvs: None,
            uvs1: None,
            indices: vec![0, 1, 2],
            material: None,
        };
        GltfScene {
            meshes: vec![MeshData { name: None, primitives: vec![primitive] }],
            instances: vec![MeshInstance { mesh: 0, world, node: None, node_name: None }],
            ..Default::default()
        }
    }

    /// Under mirroring (and non-mirroring) transforms, the spawned triangle's winding and its transformed
    /// normals agree: both give the front face glTF means (spec section 3.7.4).
    #[test]
    fn mirrored_meshes_keep_winding_and_normals_in_agreement() {
        let turn = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        for scale in [Vec3::ONE, Vec3::new(-1.0, 1.0, 1.0), Vec3::new(2.0, -0.5, 3.0), Vec3::new(-1.0, -1.0, -1.0)] {
            let world = Affine3A::from_scale_rotation_translation(scale, turn, Vec3::new(1.0, 2.0, 3.0));
            let mut w = World::new();
            let report = spawn_gltf(&mut w, &one_triangle(world));
            assert_eq!(report.meshes, 1, "{:?}", report.warnings);
            let mesh = w.query::<&Mesh>().single(&w).unwrap().clone();
            let [a, b, c] = mesh.triangle(0);
            let geometric = (b - a).cross(c - a).normalize();
            // The front normal glTF means: the local +Z carried by the inverse transpose.
            let front = (world.matrix3.inverse().transpose() * Vec3::Z).normalize();
            assert!(geometric.abs_diff_eq(front, 1e-5), "scale {scale}: winding gives {geometric}, front is {front}");
            for n in mesh.normals().unwrap() {
                assert!(n.abs_diff_eq(front, 1e-5), "scale {scale}: normal {n}, front is {front}");
            }
        }
    }
}
