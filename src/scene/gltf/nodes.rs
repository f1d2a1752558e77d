//! The node hierarchy of the chosen scene, flattened into world-space mesh instances, lights and cameras,
//! each of which remembers its node (for animation).

use ::gltf::json::camera::Type as CameraType;
use ::gltf::json::validation::Checked;
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};

use super::animation::{LocalTransform, SceneAnimations};
use super::lights::LightTable;
use super::{CameraData, Doc, LightData, MeshInstance, Warnings};

/// What the scene's nodes place in the world, and the node tree they were placed by (its
/// `clips` left for the caller).
pub(super) struct Placed {
    pub instances: Vec<MeshInstance>,
    pub lights: Vec<LightData>,
    pub cameras: Vec<CameraData>,
    pub tree: SceneAnimations,
}

/// Walks the chosen scene (the default scene, else the first, else every root node) depth first. Each node is
/// visited at most once, so cycles and nodes with two parents (both invalid glTF) cannot loop or blow up.
pub(super) fn flatten(doc: &Doc, lights: &LightTable, warnings: &mut Warnings) -> Placed {
    let nodes = &doc.root.nodes;
    let tree = SceneAnimations {
        rest: vec![
            LocalTransform::Trs { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE };
            nodes.len()
        ],
        parent: vec![None; nodes.len()],
        ..Default::default()
    };
    let mut placed = Placed { instances: Vec::new(), lights: Vec::new(), cameras: Vec::new(), tree };
    let mut visited = vec![false; nodes.len()];
    let mut stack: Vec<(usize, Option<usize>, Affine3A, String)> = scene_roots(doc, warnings)
        .into_iter()
        .rev()
        .map(|(n, pointer)| (n, None, Affine3A::IDENTITY, pointer))
        .collect();
    while let Some((n, parent_node, parent, reference)) = stack.pop() {
        let Some(node) = nodes.get(n) else {
            warnings.push(&reference, format!("node {n} does not exist ({} defined); skipped", nodes.len()));
            continue;
        };
        if std::mem::replace(&mut visited[n], true) {
            warnings.push(&reference, format!("node {n} reached a second time (cycle or two parents); skipped"));
            continue;
        }
        let pointer = format!("/nodes/{n}");
        let local = local_transform(node, &pointer, warnings);
        let world = parent * local.to_affine();
        let name = node.name.as_deref();
        placed.tree.rest[n] = local;
        placed.tree.parent[n] = parent_node;
        placed.tree.order.push(n);

        if let Some(mesh) = node.mesh.map(|m| m.value()) {
            if mesh < doc.root.meshes.len() {
                placed.instances.push(MeshInstance { mesh, world, node: Some(n), node_name: name.map(str::to_string) });
                if node.skin.is_some() {
                    warnings.push(&pointer, "skin ignored; the mesh is placed at its node transform");
                }
            } else {
                warnings.push(&format!("{pointer}/mesh"), format!("mesh {mesh} does not exist; skipped"));
            }
        }
        if let Some(camera) = node.camera.map(|c| c.value()) {
            let camera = camera_at(doc, camera, world, &format!("{pointer}/camera"), warnings);
            placed.cameras.extend(camera.map(|c| CameraData { node: Some(n), ..c }));
        }
        placed.lights.extend(lights.at_node(doc, n, name, world, warnings));
        for (k, child) in node.children.as_deref().unwrap_or_default().iter().enumerate().rev() {
            stack.push((child.value(), Some(n), world, format!("{pointer}/children/{k}")));
        }
    }
    placed
}

/// The root nodes to walk, each with the JSON pointer that names it.
fn scene_roots(doc: &Doc, warnings: &mut Warnings) -> Vec<(usize, String)> {
    let scenes = &doc.root.scenes;
    let chosen = match doc.root.scene.map(|s| s.value()) {
        Some(s) if s < scenes.len() => Some(s),
        Some(s) => {
            warnings.push("/scene", format!("scene {s} does not exist; the first scene is used"));
            (!scenes.is_empty()).then_some(0)
        }
        None => (!scenes.is_empty()).then_some(0),
    };
    match chosen {
        Some(s) => {
            scenes[s].nodes.iter().enumerate().map(|(k, n)| (n.value(), format!("/scenes/{s}/nodes/{k}"))).collect()
        }
        None => {
            // No scene: every node that is nobody's child.
            let mut is_child = vec![false; doc.root.nodes.len()];
            for child in doc.root.nodes.iter().flat_map(|n| n.children.iter().flatten()) {
                if let Some(flag) = is_child.get_mut(child.value()) {
                    *flag = true;
                }
            }
            (0..doc.root.nodes.len()).filter(|&n| !is_child[n]).map(|n| (n, format!("/nodes/{n}"))).collect()
        }
    }
}

/// The node's local transform: its matrix, or T * R * S (glTF 2.0 spec, section 3.5.2 "Transformations").
/// Non-finite values give the identity (or the default of that part) with a warning.
fn local_transform(node: &::gltf::json::Node, pointer: &str, warnings: &mut Warnings) -> LocalTransform {
    let has_trs = node.translation.is_some() || node.rotation.is_some() || node.scale.is_some();
    if let Some(m) = node.matrix {
        if has_trs {
            warnings.push(pointer, "has both matrix and translation/rotation/scale; the matrix is used");
        }
        let m = Mat4::from_cols_array(&m);
        if !m.is_finite() {
            warnings.push(&format!("{pointer}/matrix"), "NaN or infinite values; identity used");
            return LocalTransform::Matrix(Affine3A::IDENTITY);
        }
        if m.row(3) != Vec4::W {
            warnings.push(&format!("{pointer}/matrix"), "last row is not (0, 0, 0, 1); the projective part ignored");
        }
        return LocalTransform::Matrix(Affine3A::from_mat4(m));
    }
    let mut vector = |v: Option<[f32; 3]>, default: Vec3, field: &str| match v.map(Vec3::from_array) {
        Some(v) if v.is_finite() => v,
        Some(_) => {
            warnings.push(&format!("{pointer}/{field}"), format!("NaN or infinite values; {default} used"));
            default
        }
        None => default,
    };
    let translation = vector(node.translation, Vec3::ZERO, "translation");
    let scale = vector(node.scale, Vec3::ONE, "scale");
    let rotation = match node.rotation.map(|q| Quat::from_array(q.0)) {
        None => Quat::IDENTITY,
        Some(q) if q.is_finite() && q.length() > 1e-6 => q.normalize(),
        Some(q) => {
            warnings.push(&format!("{pointer}/rotation"), format!("{q} is not a rotation; identity used"));
            Quat::IDENTITY
        }
    };
    LocalTransform::Trs { translation, rotation, scale }
}

/// The perspective camera `index` placed at `world`; orthographic and invalid cameras are skipped with a warning.
fn camera_at(doc: &Doc, index: usize, world: Affine3A, reference: &str, warnings: &mut Warnings) -> Option<CameraData> {
    let Some(camera) = doc.root.cameras.get(index) else {
        warnings.push(reference, format!("camera {index} does not exist; skipped"));
        return None;
    };
    let pointer = format!("/cameras/{index}");
    let perspective = match (&camera.type_, &camera.perspective) {
        (Checked::Valid(CameraType::Perspective), Some(p)) => p,
        (Checked::Valid(CameraType::Orthographic), _) => {
            warnings.push(&pointer, "orthographic camera skipped (only perspective cameras are read)");
            return None;
        }
        _ => {
            warnings.push(&pointer, "invalid camera (bad type or no perspective object); skipped");
            return None;
        }
    };
    let (yfov, znear) = (perspective.yfov, perspective.znear);
    if !(yfov > 0.0 && yfov < std::f32::consts::PI && znear > 0.0 && znear.is_finite()) {
        warnings.push(&format!("{pointer}/perspective"), format!("yfov {yfov} or znear {znear} out of range; skipped"));
        return None;
    }
    let aspect = perspective.aspect_ratio.filter(|a| {
        let ok = a.is_finite() && *a > 0.0;
        if !ok {
            warnings.push(&format!("{pointer}/perspective/aspectRatio"), format!("{a} is not > 0; ignored"));
        }
        ok
    });
    let zfar = perspective.zfar.filter(|f| f.is_finite()).filter(|f| {
        let ok = *f > znear;
        if !ok {
            warnings.push(&format!("{pointer}/perspective/zfar"), format!("{f} is not > znear {znear}; infinite used"));
        }
        ok
    });
    Some(CameraData { name: camera.name.clone(), yfov, aspect, znear, zfar, world, node: None })
}
