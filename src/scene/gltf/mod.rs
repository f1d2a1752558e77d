//! glTF 2.0 import into plain data: triangle meshes, mesh instances with world transforms, materials and their
//! textures, punctual lights (KHR_lights_punctual, EXT_lights_ies) and perspective cameras. No ECS here: turning a
//! [`GltfScene`] into entities is the caller's business.
//!
//! kelvin reads buffers and images itself (the `gltf` crate's `import` feature is off) and deserialises the JSON
//! into `gltf::json` types, so that one bad texture or light does not lose the rest of the scene. Light extension
//! objects are read from the raw JSON, because one malformed light would otherwise fail the whole document.
//!
//! # What is read
//!
//! - `.gltf` (JSON with external `.bin` / image files or `data:` URIs, resolved relative to the file) and `.glb`.
//! - The default scene, else the first scene, else every root node; its node tree is flattened into
//!   [`MeshInstance`]s, lights and cameras with world transforms (glTF node matrices or T * R * S).
//! - Triangles (lists, strips and fans; strips and fans become lists), POSITION, NORMAL, TEXCOORD_0 and TEXCOORD_1 (lightmap uvs), in any
//!   component type (so KHR_mesh_quantization works), sparse accessors included. Skins and morph targets are
//!   ignored with a warning.
//! - Node animations (translation, rotation, scale; STEP, LINEAR, CUBICSPLINE) as [`animation::SceneAnimations`];
//!   a bad channel is dropped with a warning.
//! - A sun and sky from kelvin's root extension `KELVIN_sun_sky` ([`sky`]).
//! - Metallic-roughness materials with KHR_materials_emissive_strength, KHR_materials_specular (`specularFactor`)
//!   and KHR_materials_ior; textures on UV set 0 (PNG/JPEG, also EXR/HDR by file extension).
//!
//! # Errors and fallbacks
//!
//! A [`GltfError`] names the file and what failed; it is returned only when the geometry itself cannot be
//! trusted: unreadable file, truncated `.glb`, JSON syntax or schema errors, glTF version other than 2.x, a missing
//! or short buffer, a bad accessor or buffer view (out of bounds, wrong type, bad stride). Everything else becomes a
//! line in [`GltfScene::warnings`] (each starting with the file name and a JSON pointer like the Khronos
//! validator's) plus a fallback:
//!
//! | problem | fallback |
//! |---|---|
//! | texture file missing, unreadable or undecodable; WebP or unknown type | texture `None`, factors kept |
//! | KTX2 texture (KHR_texture_basisu; image/ktx2 or `.ktx2`) | same; warning names material, slot, factors |
//! | texture on a UV set other than 0 | texture `None` |
//! | KHR_texture_transform on a texture | transform ignored |
//! | extension in `extensionsUsed` that kelvin does not read | ignored |
//! | extension in `extensionsRequired` that kelvin does not read | ignored; the scene may look unlike intended |
//! | primitive mode points / lines / invalid; no POSITION; Draco-compressed | primitive skipped |
//! | vertex indices out of range; NaN / infinite positions | the triangles using them dropped |
//! | NaN / infinite normals; NORMAL, TEXCOORD_0 or TEXCOORD_1 count differs from POSITION's | normals (or that uv set) dropped |
//! | material index out of range | default material (`None`) |
//! | factor out of range (colour, metallic, roughness, specular); bad ior or emissive strength | clamped / default |
//! | node reached twice (cycle or shared child); bad mesh / camera / child index | that reference skipped |
//! | non-finite node transform | identity |
//! | orthographic or invalid camera | skipped |
//! | EXT_lights_ies profile missing or unreadable; light index unresolved | light dropped |
//!
//! # Policy per Khronos glTF-Validator case (`tests/data/gltf/khronos-validator`)
//!
//! No validator file gives a [`GltfError`]: each error the validator reports becomes a warning at exactly its JSON
//! pointer (one warning per error, so two errors at one pointer give two warnings), with the fallback below; lights
//! not attached to a node are checked but not placed.
//!
//! | validator case (errors) | kelvin |
//! |---|---|
//! | light/valid, node/valid, material/valid (0) | loads, no warning about lights |
//! | light/custom_property, node/custom_property, material/custom_property (0) | unknown property ignored |
//! | light/directional_light_with_range (0, info) | warning "range is ignored", `range` None |
//! | light/spot_object_with_non_spot_light (0, info) | warning "spot is ignored" |
//! | light/unknown_type (0, warning) | warning, light dropped |
//! | light/empty_light_object (1: no type) | warning, light dropped |
//! | light/empty_lights_array (1) | warning |
//! | light/empty_object (1: no `lights`) | warning |
//! | light/spot_invalid_angles (1: outer <= inner) | warning, inner set to outer (hard-edged cone) |
//! | light/spot_light_without_spot_object (1) | warning, glTF defaults (inner 0, outer pi/4) |
//! | node/empty_object (2: no `light`, no root extension) | a warning for each, reference dropped |
//! | node/unexpected_extension (1: light on a scene) | warning, ignored |
//! | node/unresolved_light_* (1-2) | warning per cause, reference dropped |
//! | material/out_of_range (1: emissiveStrength < 0) | warning, strength 1 used |
//! | material/unexpected_extension (1: strength inside pbrMetallicRoughness) | warning, ignored |
//! | material/zero_factor (0, warnings) | loads (strength has no effect) |
//!
//! Spot angles are made to satisfy 0 <= inner <= outer <= pi/2 (outer > 0); a negative light intensity becomes 0;
//! light colours are clamped to [0, 1]; a non-positive range is dropped.

mod accessor;
pub mod animation;
mod container;
mod lights;
mod material;
mod mesh;
mod nodes;
pub mod sky;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3, Vec4};
use serde::Deserialize;

use crate::scene::image::RgbImage;

/// The largest buffer (or `.gltf` / `.glb` file) accepted, in bytes (2 GiB).
pub const MAX_BUFFER_BYTES: u64 = 1 << 31;
/// The largest element count of an accessor without a buffer view (its values are zeros or sparse).
pub const MAX_VIEWLESS_ELEMENTS: u64 = 1 << 24;

/// The extensions kelvin reads; others in `extensionsUsed` give a warning.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_ior",
    "KHR_mesh_quantization",
    "EXT_lights_ies",
    sky::SUN_SKY,
];

/// A loaded glTF scene as plain data.
#[derive(Clone, Debug, Default)]
pub struct GltfScene {
    /// Every mesh of the file, indexed as in the file (instanced or not).
    pub meshes: Vec<MeshData>,
    /// The meshes placed by the chosen scene's nodes.
    pub instances: Vec<MeshInstance>,
    /// Every material of the file, indexed as in the file.
    pub materials: Vec<MaterialData>,
    /// Decoded textures referenced by [`MaterialData`] (not indexed as glTF textures: a texture used both as
    /// colour and as data appears twice). Only successfully decoded images are here.
    pub textures: Vec<Arc<RgbImage>>,
    /// Lights placed by the chosen scene's nodes, in world space (a light defined but not attached to a node of
    /// the scene is not placed).
    pub lights: Vec<LightData>,
    /// Perspective cameras placed by the chosen scene's nodes.
    pub cameras: Vec<CameraData>,
    /// The chosen scene's node tree at rest and the file's animations (`clips` is empty for a
    /// still scene).
    pub animations: animation::SceneAnimations,
    /// The sun and sky of the `KELVIN_sun_sky` root extension (see [`sky`]).
    pub sky: Option<crate::light::SunSkyLight>,
    /// What was ignored, fixed or dropped, one line each: `<file>: <JSON pointer>: <what and the fallback>`.
    pub warnings: Vec<String>,
    /// Every file the load read, each with the SHA-256 of the bytes it parsed: the scene file first (by
    /// [`load_gltf`]), then external buffers and images. (IES profiles are read when spawned.)
    pub inputs: Vec<crate::provenance::InputFile>,
}

/// A mesh: a list of triangle primitives.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// The mesh's `name`, if the file gives one.
    pub name: Option<String>,
    /// The primitives that could be read (skipped ones are in the warnings).
    pub primitives: Vec<PrimitiveData>,
}

/// A triangle list in the mesh's local frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrimitiveData {
    /// Vertex positions (metres), all finite.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, as stored (not renormalised), all finite; same length as `positions`.
    pub normals: Option<Vec<Vec3>>,
    /// TEXCOORD_0 (v = 0 at the top of the image, as glTF), same length as `positions`.
    pub uvs: Option<Vec<Vec2>>,
    /// TEXCOORD_1, the lightmap uvs of `kelvin bake` (as TEXCOORD_0: v = 0 at the top), same length as `positions`.
    pub uvs1: Option<Vec<Vec2>>,
    /// Three indices per triangle, each `< positions.len()`; never empty.
    pub indices: Vec<u32>,
    /// Index into [`GltfScene::materials`]; `None` means the glTF default material ([`MaterialData::default`]).
    pub material: Option<usize>,
}

/// A mesh placed in the world by a node.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshInstance {
    /// Index into [`GltfScene::meshes`].
    pub mesh: usize,
    /// Local-to-world transform (the product of the node and all its ancestors).
    pub world: Affine3A,
    /// The glTF node that places it.
    pub node: Option<usize>,
    /// That node's `name`, if the file gives one.
    pub node_name: Option<String>,
}

/// A metallic-roughness material (glTF 2.0 core plus the extensions kelvin reads).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialData {
    /// The material's `name`, if the file gives one.
    pub name: Option<String>,
    /// Linear RGBA base colour factor, each in [0, 1]. Defaults to 1.
    pub base_color: Vec4,
    /// Index into [`GltfScene::textures`] (sRGB-decoded to linear RGB; alpha is dropped).
    pub base_color_texture: Option<usize>,
    /// In [0, 1]. Defaults to 1.
    pub metallic: f32,
    /// Perceptual roughness in [0, 1]. Defaults to 1.
    pub roughness: f32,
    /// Index into [`GltfScene::textures`], linear data: G is roughness, B is metallic.
    pub metallic_roughness_texture: Option<usize>,
    /// Emissive factor times the emissive strength, linear RGB, each >= 0. For glTF (and kelvin, see DESIGN.md)
    /// this is luminance in nits per unit of the texture. Defaults to 0.
    pub emissive: Vec3,
    /// KHR_materials_emissive_strength, already folded into `emissive` (kept for reports). Defaults to 1.
    pub emissive_strength: f32,
    /// Index into [`GltfScene::textures`] (sRGB-decoded to linear RGB).
    pub emissive_texture: Option<usize>,
    /// Index into [`GltfScene::textures`], linear data: a tangent-space normal in [0, 1]^3.
    pub normal_texture: Option<usize>,
    /// `normalTexture.scale`: multiplies the map's x and y. Defaults to 1.
    pub normal_scale: f32,
    /// KHR_materials_specular `specularFactor` in [0, 1]. Defaults to 1.
    pub specular_factor: f32,
    /// KHR_materials_ior, >= 1. Defaults to 1.5.
    pub ior: f32,
    /// glTF `doubleSided`: the back face shades (and emits) like the front. Defaults to false.
    pub double_sided: bool,
}

impl Default for MaterialData {
    /// The glTF default material: white, fully metallic and rough, not emissive.
    fn default() -> Self {
        Self {
            name: None,
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            emissive: Vec3::ZERO,
            emissive_strength: 1.0,
            emissive_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            specular_factor: 1.0,
            ior: 1.5,
            double_sided: false,
        }
    }
}

/// The kind of a punctual light. Point, spot and IES lights sit at the node's origin; spot, directional and IES
/// lights aim along the node's local -Z axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Emits equally in every direction; intensity in candela.
    Point,
    /// Half-angles from the axis in radians, 0 <= inner <= outer <= pi/2, outer > 0.
    Spot {
        /// Half-angle of the full-intensity cone, radians.
        inner_cone_angle: f32,
        /// Half-angle beyond which the light is dark, radians.
        outer_cone_angle: f32,
    },
    /// Parallel light from infinitely far away; intensity in lux.
    Directional,
    /// EXT_lights_ies: a point light whose intensity distribution is the profile in [`LightData::ies`].
    Ies,
}

/// Where an IES profile (EXT_lights_ies) comes from; parsing it is left to `crate::scene::ies`.
#[derive(Clone, Debug, PartialEq)]
pub enum IesSource {
    /// An external file, resolved relative to the glTF file; it existed at load time.
    File(PathBuf),
    /// A `data:` URI or a buffer view; `what` names it for messages.
    Embedded {
        /// The profile's text, as stored.
        bytes: Arc<[u8]>,
        /// Names the source in messages.
        what: String,
    },
}

/// A light placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct LightData {
    /// Point, spot, directional or IES.
    pub kind: LightKind,
    /// Linear RGB colour, each in [0, 1]. Defaults to white.
    pub color: Vec3,
    /// glTF units: candela for point and spot lights, lux for directional ones; for IES lights the node's
    /// dimensionless `multiplier` on the profile's candela values. Always >= 0.
    pub intensity: f32,
    /// Distance (metres) beyond which the light may be ignored; `None` means infinite. Never set for directional
    /// or IES lights.
    pub range: Option<f32>,
    /// Local-to-world transform of the light's node.
    pub world: Affine3A,
    /// The glTF node that places it.
    pub node: Option<usize>,
    /// The light's own name (not the node's).
    pub name: Option<String>,
    /// The name of the node that places it.
    pub node_name: Option<String>,
    /// The profile of an [`LightKind::Ies`] light; `None` for every other kind.
    pub ies: Option<IesSource>,
}

/// A perspective camera looking along its node's local -Z axis, +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraData {
    /// The camera's own name (not the node's).
    pub name: Option<String>,
    /// Vertical field of view in radians, in (0, pi).
    pub yfov: f32,
    /// Width over height; `None` means "use the viewport's".
    pub aspect: Option<f32>,
    /// Near plane distance (metres), > 0.
    pub znear: f32,
    /// Far plane distance; `None` means infinite.
    pub zfar: Option<f32>,
    /// Local-to-world transform of the camera's node.
    pub world: Affine3A,
    /// The glTF node that places it.
    pub node: Option<usize>,
}

/// Why a glTF file could not be loaded. `what` names the file (or the in-memory source).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum GltfError {
    /// The file does not exist.
    #[error("{what}: file not found")]
    NotFound {
        /// The file.
        what: String,
    },
    /// The file exists but could not be read.
    #[error("{what}: cannot read: {msg}")]
    Io {
        /// The file.
        what: String,
        /// The operating system's message.
        msg: String,
    },
    /// A `.glb` container (it starts with the magic `glTF`) is truncated, of another container version, or has
    /// bad chunks.
    #[error("{what}: truncated or malformed .glb: {msg}")]
    Glb {
        /// The file or source.
        what: String,
        /// What is wrong with the container.
        msg: String,
    },
    /// The JSON does not parse.
    #[error("{what}: JSON syntax error at line {line}, column {column}: {msg}")]
    JsonSyntax {
        /// The file or source.
        what: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// The JSON parser's message.
        msg: String,
    },
    /// The JSON is not a glTF document: not an object, no `asset.version`, or fields of the wrong shape.
    #[error("{what}: not a valid glTF document: {msg}")]
    Schema {
        /// The file or source.
        what: String,
        /// What does not fit the schema.
        msg: String,
    },
    /// `asset.version` is not 2.x.
    #[error("{what}: glTF version {version:?} is not supported (2.x needed)")]
    Version {
        /// The file or source.
        what: String,
        /// The version found.
        version: String,
    },
    /// A buffer's data cannot be had: no uri and no `.glb` BIN chunk, a bad `data:` URI, or an external file
    /// that cannot be read (or no base folder to resolve it against).
    #[error("{what}: buffer {index}: cannot read {source_name}: {msg}")]
    BufferMissing {
        /// The file or source.
        what: String,
        /// Index of the buffer in `buffers`.
        index: usize,
        /// Where its data should come from (a file, the uri, "(no uri)").
        source_name: String,
        /// Why it cannot be read.
        msg: String,
    },
    /// A buffer holds fewer bytes than its `byteLength`.
    #[error(
        "{what}: buffer {index} ({source_name}) has {actual} bytes, shorter than its declared byteLength {declared}"
    )]
    BufferTooShort {
        /// The file or source.
        what: String,
        /// Index of the buffer in `buffers`.
        index: usize,
        /// Where its data came from.
        source_name: String,
        /// Its `byteLength`.
        declared: u64,
        /// The bytes actually there.
        actual: u64,
    },
    /// An accessor, buffer view or sparse index reaches past the data it refers to.
    #[error("{what}: {pointer}: out of bounds: {msg}")]
    OutOfBounds {
        /// The file or source.
        what: String,
        /// JSON pointer (RFC 6901) of the offending object.
        pointer: String,
        /// What overruns what.
        msg: String,
    },
    /// Mesh data that cannot be read: a missing accessor, buffer view or buffer, a type or component type not
    /// allowed for its use, a byteStride below the element size, bad sparse data, or too many vertices.
    #[error("{what}: {pointer}: {msg}")]
    Invalid {
        /// The file or source.
        what: String,
        /// JSON pointer (RFC 6901) of the offending object.
        pointer: String,
        /// What is wrong.
        msg: String,
    },
    /// The file, a buffer or an accessor without a buffer view is over the size kelvin reads.
    #[error("{what}: {msg}")]
    TooLarge {
        /// The file or source.
        what: String,
        /// What is too large, and the limit.
        msg: String,
    },
}

/// Loads a `.gltf` or `.glb` file; external buffers and images are resolved relative to its folder.
pub fn load_gltf(path: &Path) -> Result<GltfScene, GltfError> {
    let what = path.display().to_string();
    let bytes = container::read_file(path, &what)?;
    let mut scene = load_gltf_from_bytes(&bytes, path.parent(), &what)?;
    scene.inputs.insert(0, crate::provenance::InputFile::read(path, &bytes));
    Ok(scene)
}

pub use container::referenced_files;

/// Loads a `.gltf` (JSON) or `.glb` held in memory. `base_dir` resolves relative URIs (without it, external
/// buffers are an error and external images a warning); `what` names the source in errors and warnings.
pub fn load_gltf_from_bytes(bytes: &[u8], base_dir: Option<&Path>, what: &str) -> Result<GltfScene, GltfError> {
    let mut warnings = Warnings { what: what.to_string(), list: Vec::new() };
    let container = container::split(bytes, what, &mut warnings)?;
    let mut json = container::parse_json(container.json, what)?;
    check_version(&json, what)?;
    let raw_lights = lights::take_punctual(&mut json);
    let root = ::gltf::json::Root::deserialize(&json)
        .map_err(|e| GltfError::Schema { what: what.to_string(), msg: e.to_string() })?;
    check_extensions(&root, &mut warnings);
    let mut inputs = Vec::new();
    let buffers = container::load_buffers(&root, &json, container.bin, base_dir, what, &mut inputs)?;
    let doc = Doc { what, base_dir, root: &root, json: &json, buffers, inputs: std::cell::RefCell::new(inputs) };

    let meshes = mesh::read_meshes(&doc, &mut warnings)?;
    let (materials, textures) = material::read_materials(&doc, &mut warnings);
    let light_table = lights::LightTable::new(&doc, raw_lights, &mut warnings);
    let mut placed = nodes::flatten(&doc, &light_table, &mut warnings);
    placed.tree.clips = animation::read_clips(&doc, &placed.tree.rest, &mut warnings);
    let sky = sky::read_sky(&json, &mut warnings);
    Ok(GltfScene {
        meshes,
        instances: placed.instances,
        materials,
        textures,
        lights: placed.lights,
        cameras: placed.cameras,
        animations: placed.tree,
        sky,
        warnings: warnings.list,
        inputs: doc.inputs.into_inner(),
    })
}

/// The parsed document and its buffers, shared by the readers.
struct Doc<'a> {
    what: &'a str,
    base_dir: Option<&'a Path>,
    root: &'a ::gltf::json::Root,
    /// The raw JSON (with the KHR_lights_punctual objects taken out), for extensions `gltf::json` does not keep.
    json: &'a serde_json::Value,
    /// One per glTF buffer, exactly `byteLength` bytes long.
    buffers: Vec<Vec<u8>>,
    /// The external files read so far (buffers, then images as the readers reach them).
    inputs: std::cell::RefCell<Vec<crate::provenance::InputFile>>,
}

impl Doc<'_> {
    fn invalid(&self, pointer: impl Into<String>, msg: impl Into<String>) -> GltfError {
        GltfError::Invalid { what: self.what.to_string(), pointer: pointer.into(), msg: msg.into() }
    }

    fn out_of_bounds(&self, pointer: impl Into<String>, msg: impl Into<String>) -> GltfError {
        GltfError::OutOfBounds { what: self.what.to_string(), pointer: pointer.into(), msg: msg.into() }
    }

    /// The raw JSON at `pointer` (RFC 6901), if any.
    fn raw(&self, pointer: &str) -> Option<&serde_json::Value> {
        self.json.pointer(pointer)
    }
}

/// Warnings collected during a load, each prefixed with the file name.
struct Warnings {
    what: String,
    list: Vec<String>,
}

impl Warnings {
    fn push(&mut self, pointer: &str, msg: impl std::fmt::Display) {
        self.list.push(format!("{}: {pointer}: {msg}", self.what));
    }
}

fn check_version(json: &serde_json::Value, what: &str) -> Result<(), GltfError> {
    let Some(version) = json.pointer("/asset/version") else {
        return Err(GltfError::Schema { what: what.into(), msg: "missing asset.version".into() });
    };
    let version = version.as_str().map(str::to_string).unwrap_or_else(|| version.to_string());
    if version.split('.').next() != Some("2") {
        return Err(GltfError::Version { what: what.into(), version });
    }
    Ok(())
}

fn check_extensions(root: &::gltf::json::Root, warnings: &mut Warnings) {
    let unsupported = |list: &[String]| -> Vec<String> {
        list.iter().filter(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str())).cloned().collect()
    };
    let used = unsupported(&root.extensions_used);
    if !used.is_empty() {
        warnings.push("/extensionsUsed", format!("not supported, ignored: {}", used.join(", ")));
    }
    let required = unsupported(&root.extensions_required);
    if !required.is_empty() {
        warnings.push(
            "/extensionsRequired",
            format!(
                "required but not supported: {}; loading anyway, the scene may not look as intended",
                required.join(", ")
            ),
        );
    }
}
