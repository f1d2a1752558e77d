//! Broken files made here: truncated or short buffers, missing and garbage textures, bad accessors,
//! mutated files and JSON numbers, hard-case documents.

use super::*;

/// The binary data of one triangle: 3 positions (36 bytes), 3 uvs (24 bytes), 3 u16 indices (6 bytes).
fn triangle_bin(positions: [[f32; 3]; 3]) -> Vec<u8> {
    let mut bin = Vec::new();
    positions.iter().flatten().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0].iter().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0u16, 1, 2].iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    bin
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A one-triangle glTF whose buffer is `buffer_uri` declaring `byte_length` bytes, with a material using images
/// `base_color_uri` (base colour) and `mr_uri` (metallic-roughness).
fn triangle_json(buffer_uri: &str, byte_length: usize, base_color_uri: &str, mr_uri: &str) -> Value {
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [
            { "name": "parent", "translation": [1.0, 2.0, 3.0], "children": [1] },
            { "mesh": 0, "scale": [2.0, 2.0, 2.0] }
        ],
        "meshes": [{ "primitives": [
            { "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "indices": 2, "material": 0 }
        ] }],
        "materials": [{
            "name": "textured",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1.0, 1.0],
                "baseColorTexture": { "index": 0 },
                "metallicRoughnessTexture": { "index": 1 }
            }
        }],
        "textures": [{ "source": 0 }, { "source": 1 }],
        "images": [{ "uri": base_color_uri }, { "uri": mr_uri }],
        "buffers": [{ "uri": buffer_uri, "byteLength": byte_length }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 24 },
            { "buffer": 0, "byteOffset": 60, "byteLength": 6 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3" },
            { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" },
            { "bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ]
    })
}

fn write_json(path: &Path, json: &Value) {
    std::fs::write(path, serde_json::to_vec_pretty(json).unwrap()).unwrap();
}

/// Writes a 2x2 8-bit RGB PNG whose every texel is `rgb`.
fn write_png(path: &Path, rgb: [u8; 3]) {
    image::RgbImage::from_pixel(2, 2, image::Rgb(rgb)).save(path).unwrap();
}

#[test]
fn textured_triangle_loads_with_textures_and_transforms() {
    let dir = temp_dir("textured");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    write_png(&dir.join("base.png"), [255, 128, 0]);
    write_png(&dir.join("mr.png"), [0, 128, 255]);
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 66, "base.png", "mr.png"));
    let scene = load_ok(&dir.join("tri.gltf"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let p = &scene.meshes[0].primitives[0];
    assert_eq!((p.positions.len(), p.indices.as_slice()), (3, &[0, 1, 2][..]));
    assert_eq!(p.uvs.as_ref().unwrap()[1], glam::Vec2::new(1.0, 0.0));
    // World = T(1, 2, 3) * S(2): vertex (1, 0, 0) lands at (3, 2, 3).
    let world = scene.instances[0].world;
    assert_eq!(world.transform_point3(Vec3::X), Vec3::new(3.0, 2.0, 3.0));
    let m = &scene.materials[0];
    assert_eq!(m.base_color, Vec4::new(0.5, 0.25, 1.0, 1.0));
    // Base colour is sRGB-decoded (128 -> 0.2158605, IEC 61966-2-1); metallic-roughness stays linear (128/255).
    let base = &scene.textures[m.base_color_texture.unwrap()];
    assert!((base.get(0, 0) - Vec3::new(1.0, 0.2158605, 0.0)).abs().max_element() < 1e-5, "{}", base.get(0, 0));
    let mr = &scene.textures[m.metallic_roughness_texture.unwrap()];
    assert!((mr.get(1, 1) - Vec3::new(0.0, 128.0 / 255.0, 1.0)).abs().max_element() < 1e-5, "{}", mr.get(1, 1));
}

#[test]
fn missing_and_garbage_textures_leave_factors_and_geometry() {
    let dir = temp_dir("bad-textures");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    let mut rng = SplitMix64::new(7);
    let garbage: Vec<u8> = (0..500).map(|_| rng.next_u64() as u8).collect();
    std::fs::write(dir.join("garbage.png"), garbage).unwrap();
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 66, "no_such_texture.png", "garbage.png"));
    let scene = load_ok(&dir.join("tri.gltf"));
    let m = &scene.materials[0];
    assert_eq!((m.base_color_texture, m.metallic_roughness_texture), (None, None));
    assert_eq!(m.base_color, Vec4::new(0.5, 0.25, 1.0, 1.0));
    assert_eq!(scene.meshes[0].primitives[0].indices.len(), 3);
    assert_eq!(scene.instances.len(), 1);
    assert!(
        scene.warnings.iter().any(|w| w.contains("no_such_texture.png") && w.contains("not found")),
        "{:?}",
        scene.warnings
    );
    assert!(scene.warnings.iter().any(|w| w.contains("garbage.png")), "{:?}", scene.warnings);
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
}

#[test]
fn unsupported_image_types_and_uv_sets_warn() {
    let dir = temp_dir("ktx2");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    std::fs::write(dir.join("tex.ktx2"), b"\xABKTX 20\xBB\r\n\x1A\n").unwrap();
    let mut json = triangle_json("tri.bin", 66, "tex.ktx2", "tex.ktx2");
    json["images"][0]["mimeType"] = json!("image/ktx2");
    json["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["texCoord"] = json!(1);
    write_json(&dir.join("tri.gltf"), &json);
    let scene = load_ok(&dir.join("tri.gltf"));
    assert_eq!(scene.materials[0].base_color_texture, None);
    assert!(scene.warnings.iter().any(|w| w.contains("tex.ktx2") && w.contains("KTX2")), "{:?}", scene.warnings);
    assert!(scene.warnings.iter().any(|w| w.contains("UV set 1")), "{:?}", scene.warnings);
}

/// KTX2 textures (KHR_texture_basisu, or an image that is KTX2 by mimeType, .ktx2 uri or data: URI) are named as
/// such, with the material and the texture slot that goes without and the factors it keeps; a texture with a
/// PNG `source` beside its KHR_texture_basisu one uses the PNG, as the extension intends.
#[test]
fn ktx2_textures_are_named_with_their_material_and_slot() {
    let dir = temp_dir("ktx2-named");
    let magic = b"\xABKTX 20\xBB\r\n\x1A\n";
    std::fs::write(dir.join("tex.ktx2"), magic).unwrap();
    std::fs::write(dir.join("rough.ktx2"), magic).unwrap();
    write_png(&dir.join("fallback.png"), [255, 255, 255]);
    let json = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_texture_basisu"],
        "materials": [
            {
                "name": "painted",
                "pbrMetallicRoughness": {
                    "baseColorTexture": { "index": 0 },
                    "metallicRoughnessTexture": { "index": 1 }
                },
                "emissiveFactor": [1.0, 1.0, 1.0],
                "emissiveTexture": { "index": 2 }
            },
            { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }, "emissiveTexture": { "index": 3 } }
        ],
        "textures": [
            { "extensions": { "KHR_texture_basisu": { "source": 0 } } },
            { "source": 1 },
            { "source": 2 },
            { "source": 3, "extensions": { "KHR_texture_basisu": { "source": 0 } } }
        ],
        "images": [
            { "uri": "tex.ktx2", "mimeType": "image/ktx2" },
            { "uri": "rough.ktx2" },
            { "uri": format!("data:image/ktx2;base64,{}", base64_encode(magic)) },
            { "uri": "fallback.png" }
        ]
    });
    let path = dir.join("ktx2.gltf");
    write_json(&path, &json);
    let scene = load_ok(&path);
    let what = path.display().to_string();
    for w in &scene.warnings {
        println!("{w}");
    }
    let painted = &scene.materials[0];
    assert_eq!(
        (painted.base_color_texture, painted.metallic_roughness_texture, painted.emissive_texture),
        (None, None, None)
    );
    assert_eq!((painted.base_color, painted.emissive), (Vec4::ONE, Vec3::ONE), "factors kept");
    assert!(scene.materials[1].emissive_texture.is_some(), "the PNG source beside KHR_texture_basisu is used");
    let expect = [
        ("/materials/0/pbrMetallicRoughness/baseColorTexture", "material 0 \"painted\"", "baseColorFactor"),
        ("/materials/0/pbrMetallicRoughness/metallicRoughnessTexture", "material 0 \"painted\"", "metallicFactor"),
        ("/materials/0/emissiveTexture", "material 0 \"painted\"", "emissiveFactor"),
        ("/materials/1/pbrMetallicRoughness/baseColorTexture", "material 1", "baseColorFactor"),
    ];
    for (pointer, material, factor) in expect {
        let slot = pointer.rsplit('/').next().unwrap();
        assert!(
            scene.warnings.iter().any(|w| warning_pointer(w, &what) == pointer
                && w.contains("KTX2 (Basis Universal, KHR_texture_basisu) textures are not supported")
                && w.contains(material)
                && w.contains(slot)
                && w.contains(factor)),
            "no KTX2 warning at {pointer} naming {material}, {slot} and {factor}: {:#?}",
            scene.warnings
        );
    }
    assert!(!scene.warnings.iter().any(|w| w.contains("unsupported image type")), "{:#?}", scene.warnings);
    // The four above and /extensionsUsed (KHR_texture_basisu is not read).
    assert_eq!(scene.warnings.len(), 5, "{:#?}", scene.warnings);
}

#[test]
fn missing_bin_is_an_error_naming_it() {
    let dir = temp_dir("missing-bin");
    write_json(&dir.join("tri.gltf"), &triangle_json("missing.bin", 66, "a.png", "b.png"));
    let err = load_gltf(&dir.join("tri.gltf")).unwrap_err();
    assert!(matches!(err, GltfError::BufferMissing { .. }), "{err}");
    assert!(err.to_string().contains("missing.bin") && err.to_string().contains("tri.gltf"), "{err}");
}

#[test]
fn buffer_shorter_than_declared_is_an_error() {
    let dir = temp_dir("short-bin");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 80, "a.png", "b.png"));
    let err = load_gltf(&dir.join("tri.gltf")).unwrap_err();
    assert!(matches!(err, GltfError::BufferTooShort { declared: 80, actual: 66, .. }), "{err}");
    assert!(err.to_string().contains("tri.bin"), "{err}");
}

#[test]
fn accessor_out_of_bounds_is_an_error() {
    let mut json = triangle_json("", 66, "a.png", "b.png");
    let bin = triangle_bin(TRIANGLE);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64_encode(&bin)));
    // Data-URI buffer, no base directory: loads (external images only warn).
    let scene = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap();
    assert_eq!(scene.meshes[0].primitives[0].positions.len(), 3);
    assert!(scene.warnings.iter().any(|w| w.contains("no base directory")), "{:?}", scene.warnings);

    json["accessors"][0]["count"] = json!(4);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(matches!(&err, GltfError::OutOfBounds { pointer, .. } if pointer == "/accessors/0"), "{err}");
    json["accessors"][0]["count"] = json!(3);
    json["bufferViews"][2]["byteLength"] = json!(600);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(matches!(&err, GltfError::OutOfBounds { pointer, .. } if pointer == "/bufferViews/2"), "{err}");
    json["bufferViews"][2]["byteLength"] = json!(6);
    json["bufferViews"][0]["byteStride"] = json!(4);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(err.to_string().contains("byteStride 4"), "{err}");
}

#[test]
fn nan_vertices_drop_their_triangles() {
    let dir = temp_dir("nan");
    let mut positions = [[0.0f32; 3]; 6];
    positions[..3].copy_from_slice(&TRIANGLE);
    positions[3..].copy_from_slice(&[[0.0, 0.0, 1.0], [f32::NAN, 0.0, 1.0], [0.0, 1.0, 1.0]]);
    let mut bin = Vec::new();
    positions.iter().flatten().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    std::fs::write(dir.join("nan.bin"), &bin).unwrap();
    let json = json!({
        "asset": { "version": "2.0" },
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "buffers": [{ "uri": "nan.bin", "byteLength": 72 }],
        "bufferViews": [{ "buffer": 0, "byteLength": 72 }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3" }]
    });
    write_json(&dir.join("nan.gltf"), &json);
    let scene = load_ok(&dir.join("nan.gltf"));
    assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
    assert!(scene.warnings.iter().any(|w| w.contains("1 triangle(s) with NaN")), "{:?}", scene.warnings);
    // The unused NaN vertex is replaced, so every position is finite as documented.
    assert!(scene.meshes[0].primitives[0].positions.iter().all(|p| p.is_finite()));
}

#[test]
fn truncated_glb_and_bad_json_are_errors() {
    let dir = gltf_dir();
    let bytes = std::fs::read(dir.join("bevy/CornellBox.glb")).unwrap();
    let tmp = temp_dir("truncated");
    for cut in [6, 12, 19, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(tmp.join("cut.glb"), &bytes[..cut]).unwrap();
        let err = load_gltf(&tmp.join("cut.glb")).unwrap_err();
        assert!(matches!(err, GltfError::Glb { .. }), "cut at {cut}: {err}");
        assert!(err.to_string().contains("cut.glb"), "{err}");
    }
    let err = load_gltf_from_bytes(b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [,]\n}", None, "bad.gltf")
        .unwrap_err();
    assert!(matches!(err, GltfError::JsonSyntax { line: 3, .. }), "{err}");
    let err = load_gltf_from_bytes(br#"{"asset": {"version": "1.0"}}"#, None, "old.gltf").unwrap_err();
    assert!(matches!(err, GltfError::Version { .. }), "{err}");
    let err = load_gltf(&tmp.join("nowhere.glb")).unwrap_err();
    assert!(matches!(err, GltfError::NotFound { .. }), "{err}");
}

/// A real .gltf next to a truncated (or empty) copy of its .bin: an error naming both files and both lengths.
#[test]
fn real_gltf_with_truncated_bin_is_an_error_naming_it() {
    let dir = gltf_dir();
    let src = dir.join("renderling");
    let bin = std::fs::read(src.join("shadow_mapping_sanity.bin")).unwrap();
    let tmp = temp_dir("truncated-bin");
    std::fs::copy(src.join("shadow_mapping_sanity.gltf"), tmp.join("scene.gltf")).unwrap();
    for cut in [0, 1, bin.len() / 2, bin.len() - 1] {
        std::fs::write(tmp.join("shadow_mapping_sanity.bin"), &bin[..cut]).unwrap();
        let err = load_gltf(&tmp.join("scene.gltf")).unwrap_err();
        let declared = bin.len() as u64;
        assert!(
            matches!(err, GltfError::BufferTooShort { declared: d, actual, .. } if d == declared && actual == cut as u64),
            "cut at {cut}: {err}"
        );
        let msg = err.to_string();
        assert!(msg.contains("scene.gltf") && msg.contains("shadow_mapping_sanity.bin"), "{msg}");
    }
    // The whole .bin loads.
    std::fs::write(tmp.join("shadow_mapping_sanity.bin"), &bin).unwrap();
    assert!(!load_ok(&tmp.join("scene.gltf")).instances.is_empty());
}

/// Random byte flips and truncations of real files never panic (each gives a scene or an error).
#[test]
fn mutated_files_never_panic() {
    let dir = gltf_dir();
    let mut rng = SplitMix64::new(2024);
    for file in ["bevy/CornellBox.glb", "kajiya/emissive_triangle/triangle.glb", "renderling/spot_lights.glb"] {
        let original = std::fs::read(dir.join(file)).unwrap();
        let (mut loaded, mut failed) = (0, 0);
        for _ in 0..300 {
            let mut bytes = original.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                bytes[at] = rng.next_u64() as u8;
            }
            if rng.below(4) == 0 {
                bytes.truncate(rng.below(bytes.len()));
            }
            match load_gltf_from_bytes(&bytes, None, file) {
                Ok(_) => loaded += 1,
                Err(_) => failed += 1,
            }
        }
        println!("{file}: {loaded} mutated copies loaded, {failed} refused");
    }
}

fn base64_encode(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A data: URI holding `bytes`.
fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64_encode(bytes))
}

#[test]
fn hard_cases_strips_points_cycles_and_bad_references() {
    // Four vertices of a unit square, used as a strip, as points and as a list with an index out of range.
    let mut bin = Vec::new();
    [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]
        .iter()
        .flatten()
        .for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0u16, 1, 2, 2, 1, 9].iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    let json = json!({
        "asset": { "version": "2.0" },
        "scenes": [{ "nodes": [0, 5] }],
        "nodes": [{ "children": [1] }, { "mesh": 0, "children": [0, 2] }, { "mesh": 3 }],
        "meshes": [{ "primitives": [
            { "attributes": { "POSITION": 0 }, "mode": 5 },
            { "attributes": { "POSITION": 0 }, "mode": 0 },
            { "attributes": { "POSITION": 0 }, "indices": 1, "material": 7 },
            { "attributes": { "NORMAL": 0 } }
        ] }],
        "buffers": [{ "uri": data_uri(&bin), "byteLength": bin.len() }],
        "bufferViews": [{ "buffer": 0, "byteLength": 48 }, { "buffer": 0, "byteOffset": 48, "byteLength": 12 }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let scene = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "hard.gltf").unwrap();
    let prims = &scene.meshes[0].primitives;
    assert_eq!(prims.len(), 2, "{:?}", scene.warnings);
    assert_eq!(prims[0].indices, vec![0, 1, 2, 1, 3, 2]); // strip, winding kept
    assert_eq!((prims[1].indices.as_slice(), prims[1].material), (&[0, 1, 2][..], None));
    assert_eq!(scene.instances.len(), 1);
    let expect = [
        "/meshes/0/primitives/1: mode Points",
        "/meshes/0/primitives/2: 1 triangle(s) with vertex indices >= 4",
        "/meshes/0/primitives/2/material: material 7 does not exist",
        "/meshes/0/primitives/3: no POSITION",
        "/scenes/0/nodes/1: node 5 does not exist",
        "/nodes/1/children/0: node 0 reached a second time",
        "/nodes/2/mesh: mesh 3 does not exist",
    ];
    for e in expect {
        assert!(scene.warnings.iter().any(|w| w.contains(e)), "no warning {e:?} in {:#?}", scene.warnings);
    }
    assert_eq!(scene.warnings.len(), expect.len(), "{:#?}", scene.warnings);
}

/// TEXCOORD_1 (lightmap uvs) is read as TEXCOORD_0 is: a set with the wrong count is dropped with
/// a warning at the primitive's pointer, non-finite values become (0, 0) with one.
#[test]
fn lightmap_uvs_are_read_and_checked_as_the_first_set() {
    let mut bin = triangle_bin(TRIANGLE);
    // Two more uv sets after the indices (and 2 bytes of padding): 2 uvs, and 3 with a NaN.
    bin.extend([0u8; 2]);
    [0.5f32, 0.5, 1.0, 1.0, 0.25, f32::NAN, 0.5, 0.5, 0.75, 0.75].iter().for_each(|x| bin.extend(x.to_le_bytes()));
    let mut json = triangle_json(&data_uri(&bin), bin.len(), "", "");
    let root = json.as_object_mut().unwrap();
    root.remove("materials");
    root.remove("textures");
    root.remove("images");
    json["bufferViews"].as_array_mut().unwrap().extend([
        json!({ "buffer": 0, "byteOffset": 68, "byteLength": 16 }),
        json!({ "buffer": 0, "byteOffset": 84, "byteLength": 24 }),
    ]);
    json["accessors"].as_array_mut().unwrap().extend([
        json!({ "bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC2" }),
        json!({ "bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC2" }),
    ]);
    let primitive =
        |uv1: usize| json!({ "attributes": { "POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": uv1 }, "indices": 2 });
    json["meshes"][0]["primitives"] = json!([primitive(1), primitive(3), primitive(4)]);
    let scene = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "uv1.gltf").unwrap();
    let prims = &scene.meshes[0].primitives;
    let uv = |x: f32, y: f32| glam::Vec2::new(x, y);
    assert_eq!(prims[0].uvs1, Some(vec![uv(0.0, 0.0), uv(1.0, 0.0), uv(0.0, 1.0)]));
    assert_eq!(prims[1].uvs1, None);
    assert_eq!(prims[2].uvs1, Some(vec![uv(0.0, 0.0), uv(0.5, 0.5), uv(0.75, 0.75)]));
    assert_eq!(prims[1].uvs, prims[0].uvs, "TEXCOORD_0 is kept when TEXCOORD_1 is dropped");
    let expect = [
        "uv1.gltf: /meshes/0/primitives/1: TEXCOORD_1 count differs from POSITION count 3; uvs dropped",
        "uv1.gltf: /meshes/0/primitives/2: 1 NaN or infinite TEXCOORD_1 value(s) set to (0, 0)",
    ];
    assert_eq!(scene.warnings, expect);
}

#[test]
fn ies_lights_are_resolved_relative_to_the_file() {
    let dir = temp_dir("ies");
    std::fs::write(dir.join("lamp.ies"), "IESNA:LM-63-2002\nTILT=NONE\n").unwrap();
    let profile = b"IESNA:LM-63-1995\n";
    let json = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["EXT_lights_ies"],
        "extensions": { "EXT_lights_ies": { "lights": [
            { "uri": "lamp.ies" },
            { "uri": "missing.ies" },
            { "bufferView": 0, "mimeType": "application/x-ies-lm-63" }
        ] } },
        "nodes": [
            {
                "translation": [0.0, 3.0, 0.0],
                "extensions": { "EXT_lights_ies": { "light": 0, "multiplier": 2.5, "color": [1.0, 0.5, 0.25] } }
            },
            { "extensions": { "EXT_lights_ies": { "light": 1 } } },
            { "extensions": { "EXT_lights_ies": { "light": 2 } } },
            { "extensions": { "EXT_lights_ies": { "light": 3 } } }
        ],
        "buffers": [{ "uri": data_uri(profile), "byteLength": profile.len() }],
        "bufferViews": [{ "buffer": 0, "byteLength": profile.len() }]
    });
    write_json(&dir.join("ies.gltf"), &json);
    let scene = load_ok(&dir.join("ies.gltf"));
    assert_eq!(scene.lights.len(), 2, "{:#?}", scene.warnings);
    let lamp = &scene.lights[0];
    assert_eq!((lamp.kind, lamp.intensity, lamp.color), (LightKind::Ies, 2.5, Vec3::new(1.0, 0.5, 0.25)));
    assert_eq!(lamp.world.translation, glam::Vec3A::new(0.0, 3.0, 0.0));
    assert_eq!(lamp.ies, Some(IesSource::File(dir.join("lamp.ies"))));
    match &scene.lights[1].ies {
        Some(IesSource::Embedded { bytes, .. }) => assert_eq!(&bytes[..], profile),
        other => panic!("expected an embedded profile, got {other:?}"),
    }
    assert!(
        scene.warnings.iter().any(|w| w.contains("missing.ies") && w.contains("not found")),
        "{:#?}",
        scene.warnings
    );
    assert!(scene.warnings.iter().any(|w| w.contains("IES light 3 unresolved")), "{:#?}", scene.warnings);
}

/// Numbers in a real file's JSON (indices, counts, offsets, strides, factors) replaced by hostile values never
/// panic: each copy gives a scene or an error.
#[test]
fn mutated_json_numbers_never_panic() {
    let dir = gltf_dir();
    let base = dir.join("renderling");
    let original: Value =
        serde_json::from_slice(&std::fs::read(base.join("shadow_mapping_sanity.gltf")).unwrap()).unwrap();
    /// JSON pointers of every number in `v`.
    fn numbers(v: &Value, at: String, out: &mut Vec<String>) {
        match v {
            Value::Number(_) => out.push(at),
            Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| numbers(x, format!("{at}/{i}"), out)),
            Value::Object(o) => o.iter().for_each(|(k, x)| numbers(x, format!("{at}/{k}"), out)),
            _ => {}
        }
    }
    let mut slots = Vec::new();
    numbers(&original, String::new(), &mut slots);
    let hostile = [
        json!(0),
        json!(1),
        json!(-1),
        json!(3),
        json!(7),
        json!(255),
        json!(65535),
        json!(4294967295u64),
        json!(1e30),
        json!(-0.5),
        json!(0.5),
        json!(5120),
        json!(5125),
        json!(u64::MAX),
    ];
    let mut rng = SplitMix64::new(99);
    let (mut loaded, mut failed) = (0, 0);
    for _ in 0..200 {
        let mut json = original.clone();
        for _ in 0..1 + rng.below(3) {
            let slot = &slots[rng.below(slots.len())];
            *json.pointer_mut(slot).unwrap() = hostile[rng.below(hostile.len())].clone();
        }
        match load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), Some(&base), "mutated.gltf") {
            Ok(_) => loaded += 1,
            Err(_) => failed += 1,
        }
    }
    println!("shadow_mapping_sanity.gltf: {loaded} mutated copies loaded, {failed} refused");
    assert!(loaded > 0 && failed > 0);
}
