//! Node animation where it makes a shear: a rotated node whose non-uniform scale is animated,
//! and a rotating child of a non-uniformly scaled parent. A mesh's vertices are baked in world
//! space at rest and its `Transform` is the change since then, pose x rest^-1, which shears in
//! both cases; posed vertices are checked against the glTF spec's world matrices (parent x T R S)
//! computed here by hand, as the transform gives them and as the scene BVH's rays find them.
//! Also: a zero-length rotation keyframe is dropped with a warning instead of posing NaN.

use base64::Engine;
use bevy_ecs::prelude::*;
use glam::{Mat3, Quat, Vec3};
use kelvin::geometry::{Mesh, Ray, SceneBvh, Transform};
use kelvin::scene::animate::{GltfNode, pose_gltf};
use kelvin::scene::gltf::load_gltf_from_bytes;
use kelvin::scene::spawn::spawn_gltf;
use kelvin::systems::LightingPlugin;

const TRIANGLE: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];
/// Node 0 "rotated": translation (-3, 0, 0), a fixed 30 degree turn about z, scale animated.
const ROTATED_T: Vec3 = Vec3::new(-3.0, 0.0, 0.0);
/// Node 1 "parent": scale (2, 1, 1); its child node 2 at (3, 0, 0) turns about z.
const PARENT_SCALE: Vec3 = Vec3::new(2.0, 1.0, 1.0);
const CHILD_T: Vec3 = Vec3::new(1.5, 0.0, 0.0);
const SCALES: [Vec3; 2] = [Vec3::ONE, Vec3::new(2.0, 0.5, 1.0)];

fn rotated_r() -> Quat {
    Quat::from_rotation_z(30f32.to_radians())
}

fn child_rotations() -> [Quat; 2] {
    [Quat::IDENTITY, Quat::from_rotation_z(60f32.to_radians())]
}

/// The file: one triangle mesh used by nodes 0 and 2, one animation of two LINEAR channels over
/// one second (node 0's scale, node 2's rotation); `rotation_out` overrides node 2's keys.
fn file(rotation_out: [Quat; 2]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut put = |v: &[f32]| v.iter().for_each(|x| bytes.extend(x.to_le_bytes()));
    TRIANGLE.iter().for_each(|v| put(&v.to_array()));
    put(&[0.0, 1.0]);
    SCALES.iter().for_each(|v| put(&v.to_array()));
    rotation_out.iter().for_each(|q| put(&q.to_array()));
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bytes));
    let view =
        |offset: usize, length: usize| serde_json::json!({ "buffer": 0, "byteOffset": offset, "byteLength": length });
    let (r, p) = (rotated_r().to_array(), PARENT_SCALE.to_array());
    let json = serde_json::json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": uri, "byteLength": bytes.len() }],
        "bufferViews": [view(0, 36), view(36, 8), view(44, 24), view(68, 32)],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1] },
            { "bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3" },
            { "bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC4" }
        ],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "nodes": [
            { "name": "rotated", "mesh": 0, "translation": ROTATED_T.to_array(), "rotation": r },
            { "name": "parent", "scale": p, "children": [2] },
            { "name": "child", "mesh": 0, "translation": CHILD_T.to_array() }
        ],
        "scenes": [{ "nodes": [0, 1] }],
        "scene": 0,
        "animations": [{
            "channels": [
                { "sampler": 0, "target": { "node": 0, "path": "scale" } },
                { "sampler": 1, "target": { "node": 2, "path": "rotation" } }
            ],
            "samplers": [
                { "input": 1, "output": 2, "interpolation": "LINEAR" },
                { "input": 1, "output": 3, "interpolation": "LINEAR" }
            ]
        }]
    });
    serde_json::to_vec(&json).unwrap()
}

/// The world matrix of a mesh node at time `t`, from the spec: parent x T x R x S, the keys
/// interpolated linearly (slerp for rotations).
fn by_hand(node: usize, t: f32) -> glam::Affine3A {
    use glam::Affine3A;
    match node {
        0 => Affine3A::from_scale_rotation_translation(SCALES[0].lerp(SCALES[1], t), rotated_r(), ROTATED_T),
        _ => {
            let [q0, q1] = child_rotations();
            let child = Affine3A::from_rotation_translation(q0.slerp(q1, t), CHILD_T);
            Affine3A::from_scale(PARENT_SCALE) * child
        }
    }
}

#[test]
fn sheared_poses_keep_their_shear_in_the_transform_and_the_bvh() {
    let scene = load_gltf_from_bytes(&file(child_rotations()), None, "shear.gltf").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    spawn_gltf(&mut world, &scene);
    schedule.run(&mut world);
    for t in [0.5f32, 1.0] {
        pose_gltf(&mut world, 0, 0, t).unwrap();
        schedule.run(&mut world);
        let mut query = world.query::<(&GltfNode, &Transform, &Mesh)>();
        let meshes: Vec<(usize, Transform, Vec<Vec3>)> =
            query.iter(&world).map(|(n, tr, m)| (n.node, *tr, m.positions().to_vec())).collect();
        assert_eq!(meshes.len(), 2);
        for (node, transform, rest) in meshes {
            let want: Vec<Vec3> = TRIANGLE.iter().map(|&v| by_hand(node, t).transform_point3(v)).collect();
            let posed: Vec<Vec3> = rest.iter().map(|&p| transform.transform_point(p)).collect();
            let error = want.iter().zip(&posed).map(|(a, b)| (*a - *b).length()).fold(0.0f32, f32::max);
            eprintln!("node {node} at t = {t}: shear {}, largest vertex error {error:.2e} m", transform.shear);
            assert!(transform.is_sheared(), "node {node} at t = {t}: the change since rest shears");
            assert!(error < 1e-5, "node {node} at t = {t}: posed {posed:?}, by hand {want:?}");
            // Rays find the posed triangle: just inside each corner, and not just outside.
            let bvh = world.resource::<SceneBvh>();
            let centre = (want[0] + want[1] + want[2]) / 3.0;
            for corner in &want {
                for (inside, s) in [(true, 0.98f32), (false, 1.05)] {
                    let p = centre + (*corner - centre) * s;
                    let hit =
                        bvh.closest_hit(&Ray::new(p + Vec3::Z, Vec3::NEG_Z)).filter(|h| (h.p - p).length() < 1e-4);
                    assert_eq!(hit.is_some(), inside, "node {node} at t = {t}: ray at {p} (inside: {inside})");
                }
            }
        }
    }
}

/// Normals follow the shear by the inverse transpose: a posed triangle's smooth normal stays
/// perpendicular to its posed edges.
#[test]
fn a_sheared_transform_maps_normals_by_the_inverse_transpose() {
    let m = glam::Affine3A::from_scale(PARENT_SCALE)
        * glam::Affine3A::from_rotation_z(1.0)
        * glam::Affine3A::from_scale(Vec3::new(1.0, 3.0, 0.5));
    let t = Transform::from_affine(m);
    assert!(t.is_sheared());
    let edges = [Vec3::new(1.0, 2.0, 0.5), Vec3::new(-0.3, 0.4, 2.0)];
    let normal = edges[0].cross(edges[1]);
    let n = t.transform_normal(normal).normalize();
    for e in edges {
        let posed = t.transform_vector(e).normalize();
        assert!(n.dot(posed).abs() < 1e-5, "normal {n} against posed edge {posed}");
        assert!((m.transform_vector3(e).normalize() - posed).length() < 1e-5, "from_affine keeps the matrix");
    }
    assert!((Mat3::from(t.to_affine().matrix3) - Mat3::from(m.matrix3)).abs_diff_eq(Mat3::ZERO, 1e-5));
}

/// Hard case: a rotation keyframe of zero length has no rotation; slerping or normalising it
/// gave NaN poses. The channel is dropped with a warning at its pointer; the other channel plays.
#[test]
fn a_zero_length_rotation_key_drops_its_channel_with_a_warning() {
    let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let scene = load_gltf_from_bytes(&file([Quat::IDENTITY, zero]), None, "zero.gltf").unwrap();
    let warnings = scene.warnings.join("\n");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.starts_with("zero.gltf: /animations/0/channels/1: ") && w.contains("zero length")),
        "{warnings}"
    );
    assert_eq!(scene.animations.clips[0].channels.len(), 1, "{warnings}");
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    spawn_gltf(&mut world, &scene);
    pose_gltf(&mut world, 0, 0, 0.7).unwrap();
    let mut query = world.query::<&Transform>();
    assert!(query.iter(&world).all(|t| t.to_affine().is_finite()));
}
