//! Materials and their textures. Nothing here is fatal: a bad value is clamped or defaulted, a texture that cannot
//! be loaded leaves the material with its factors; each with a warning.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::accessor::view_bytes;
use super::container::{UriTarget, resolve_uri, shorten};
use super::{Doc, MaterialData, Warnings};
use crate::scene::image::{ImageFormat, RgbImage, load_image_from_bytes};
use crate::spectrum::color::srgb_encode;

/// How a texture's texels are meant (glTF 2.0 spec, section 3.9: colour textures are sRGB-encoded, the others
/// hold linear data).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Encoding {
    Srgb,
    Linear,
}

/// Decoded images, so that an image shared by several materials is decoded (and warned about) once.
struct TextureCache {
    /// (glTF image index, encoding) -> index into `images`, or `None` when it failed.
    loaded: HashMap<(usize, Encoding), Option<usize>>,
    images: Vec<Arc<RgbImage>>,
}

/// Reads every material (indexed as in the file) and the textures they use.
pub(super) fn read_materials(doc: &Doc, warnings: &mut Warnings) -> (Vec<MaterialData>, Vec<Arc<RgbImage>>) {
    let mut cache = TextureCache { loaded: HashMap::new(), images: Vec::new() };
    let materials =
        doc.root.materials.iter().enumerate().map(|(i, m)| read_material(doc, i, m, &mut cache, warnings)).collect();
    (materials, cache.images)
}

fn read_material(
    doc: &Doc,
    index: usize,
    material: &::gltf::json::Material,
    cache: &mut TextureCache,
    warnings: &mut Warnings,
) -> MaterialData {
    let pointer = format!("/materials/{index}");
    let pbr = &material.pbr_metallic_roughness;
    let mut unit = |value: f32, field: &str| clamp_unit(value, &format!("{pointer}/{field}"), warnings);
    let f = pbr.base_color_factor.0;
    let base_color = Vec4::new(
        unit(f[0], "pbrMetallicRoughness/baseColorFactor/0"),
        unit(f[1], "pbrMetallicRoughness/baseColorFactor/1"),
        unit(f[2], "pbrMetallicRoughness/baseColorFactor/2"),
        unit(f[3], "pbrMetallicRoughness/baseColorFactor/3"),
    );
    let metallic = unit(pbr.metallic_factor.0, "pbrMetallicRoughness/metallicFactor");
    let roughness = unit(pbr.roughness_factor.0, "pbrMetallicRoughness/roughnessFactor");
    let e = material.emissive_factor.0;
    let emissive_factor =
        Vec3::new(unit(e[0], "emissiveFactor/0"), unit(e[1], "emissiveFactor/1"), unit(e[2], "emissiveFactor/2"));

    let ext = material.extensions.as_ref();
    let mut emissive_strength = ext.and_then(|x| x.emissive_strength.as_ref()).map_or(1.0, |s| s.emissive_strength.0);
    if !(emissive_strength.is_finite() && emissive_strength >= 0.0) {
        warnings.push(
            &format!("{pointer}/extensions/KHR_materials_emissive_strength/emissiveStrength"),
            format!("{emissive_strength} is out of range (must be >= 0); strength 1 used"),
        );
        emissive_strength = 1.0;
    }
    let misplaced = format!("{pointer}/pbrMetallicRoughness/extensions/KHR_materials_emissive_strength");
    if doc.raw(&misplaced).is_some() {
        warnings.push(&misplaced, "KHR_materials_emissive_strength belongs on the material itself; ignored here");
    }
    let specular_factor = ext.and_then(|x| x.specular.as_ref()).map_or(1.0, |s| {
        clamp_unit(
            s.specular_factor.0,
            &format!("{pointer}/extensions/KHR_materials_specular/specularFactor"),
            warnings,
        )
    });
    let mut ior = ext.and_then(|x| x.ior.as_ref()).map_or(1.5, |i| i.ior.0);
    if !(ior.is_finite() && ior >= 1.0) {
        warnings.push(&format!("{pointer}/extensions/KHR_materials_ior/ior"), format!("{ior} is not >= 1; 1.5 used"));
        ior = 1.5;
    }

    let label = match &material.name {
        Some(name) => format!("material {index} {name:?}"),
        None => format!("material {index}"),
    };
    let info = |i: &::gltf::json::texture::Info| (i.index.value(), i.tex_coord);
    let normal = material.normal_texture.as_ref();
    let mut normal_scale = normal.map_or(1.0, |n| n.scale);
    if !normal_scale.is_finite() {
        warnings.push(&format!("{pointer}/normalTexture/scale"), format!("{normal_scale} is not finite; 1 used"));
        normal_scale = 1.0;
    }
    let mut texture = |info: Option<(usize, u32)>, slot: SlotKind, encoding: Encoding| {
        let slot = Slot { pointer: format!("{pointer}/{}", slot.field()), material: &label, kind: slot };
        info.and_then(|info| texture_index(doc, info, &slot, encoding, cache, warnings))
    };

    MaterialData {
        name: material.name.clone(),
        base_color,
        base_color_texture: texture(pbr.base_color_texture.as_ref().map(info), SlotKind::BaseColor, Encoding::Srgb),
        metallic,
        roughness,
        metallic_roughness_texture: texture(
            pbr.metallic_roughness_texture.as_ref().map(info),
            SlotKind::MetallicRoughness,
            Encoding::Linear,
        ),
        emissive: emissive_factor * emissive_strength,
        emissive_strength,
        emissive_texture: texture(material.emissive_texture.as_ref().map(info), SlotKind::Emissive, Encoding::Srgb),
        normal_texture: texture(normal.map(|n| (n.index.value(), n.tex_coord)), SlotKind::Normal, Encoding::Linear),
        normal_scale,
        specular_factor,
        ior,
        double_sided: material.double_sided,
    }
}

/// `value` clamped to [0, 1] (NaN to 0), with a warning when it changed.
fn clamp_unit(value: f32, pointer: &str, warnings: &mut Warnings) -> f32 {
    if (0.0..=1.0).contains(&value) {
        return value;
    }
    let fixed = if value.is_nan() { 0.0 } else { value.clamp(0.0, 1.0) };
    warnings.push(pointer, format!("{value} is outside [0, 1]; {fixed} used"));
    fixed
}

/// The texture slots kelvin reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SlotKind {
    BaseColor,
    MetallicRoughness,
    Emissive,
    Normal,
}

impl SlotKind {
    /// The slot's path under the material.
    fn field(self) -> &'static str {
        match self {
            Self::BaseColor => "pbrMetallicRoughness/baseColorTexture",
            Self::MetallicRoughness => "pbrMetallicRoughness/metallicRoughnessTexture",
            Self::Emissive => "emissiveTexture",
            Self::Normal => "normalTexture",
        }
    }

    /// The slot's property name.
    fn name(self) -> &'static str {
        self.field().rsplit('/').next().unwrap_or_default()
    }

    /// The factors the material is drawn with when the texture is not used.
    fn factors(self) -> &'static str {
        match self {
            Self::BaseColor => "baseColorFactor",
            Self::MetallicRoughness => "metallicFactor and roughnessFactor",
            Self::Emissive => "emissiveFactor",
            Self::Normal => "interpolated normals",
        }
    }
}

/// A material's texture slot, for pointers and messages.
struct Slot<'a> {
    /// JSON pointer of the slot's textureInfo.
    pointer: String,
    /// `material <index>`, with its name in quotes when it has one.
    material: &'a str,
    kind: SlotKind,
}

impl Slot<'_> {
    /// What the material does without this texture.
    fn fallback(&self) -> String {
        format!("{} keeps its {} without its {}", self.material, self.kind.factors(), self.kind.name())
    }
}

/// The media type of KTX2 images (KHR_texture_basisu).
const KTX2_MIME: &str = "image/ktx2";
/// The first 12 bytes of every KTX2 file.
const KTX2_MAGIC: &[u8] = b"\xABKTX 20\xBB\r\n\x1A\n";
const KTX2_UNSUPPORTED: &str = "KTX2 (Basis Universal, KHR_texture_basisu) textures are not supported";

/// Whether glTF image `index` is KTX2: by its mimeType, its uri (a `.ktx2` path or a `data:image/ktx2` URI) or,
/// in a buffer view, its first bytes.
fn is_ktx2(doc: &Doc, index: usize) -> bool {
    let image = &doc.root.images[index];
    if image.mime_type.as_ref().is_some_and(|m| m.0.trim().eq_ignore_ascii_case(KTX2_MIME)) {
        return true;
    }
    match (&image.uri, image.buffer_view) {
        (Some(uri), _) => match uri.strip_prefix("data:") {
            Some(rest) => rest.split([';', ',']).next().is_some_and(|m| m.trim().eq_ignore_ascii_case(KTX2_MIME)),
            None => {
                let path = uri.split(['?', '#']).next().unwrap_or_default();
                Path::new(path).extension().is_some_and(|e| e.eq_ignore_ascii_case("ktx2"))
            }
        },
        (None, Some(view)) => view_bytes(doc, view.value()).is_ok_and(|(bytes, _)| bytes.starts_with(KTX2_MAGIC)),
        (None, None) => false,
    }
}

/// The index in `cache.images` of texture `t` (read through UV set `tex_coord`), or `None` (with a warning) if it cannot be used.
fn texture_index(
    doc: &Doc,
    (t, tex_coord): (usize, u32),
    slot: &Slot,
    encoding: Encoding,
    cache: &mut TextureCache,
    warnings: &mut Warnings,
) -> Option<usize> {
    let pointer = slot.pointer.as_str();
    if tex_coord != 0 {
        warnings.push(pointer, format!("uses UV set {tex_coord}; only TEXCOORD_0 is read, texture ignored"));
        return None;
    }
    if doc.raw(&format!("{pointer}/extensions/KHR_texture_transform")).is_some() {
        warnings.push(pointer, "KHR_texture_transform ignored (texture used untransformed)");
    }
    let Some(texture) = doc.root.textures.get(t) else {
        warnings.push(pointer, format!("texture {t} does not exist: {}", slot.fallback()));
        return None;
    };
    let image = texture.source.value();
    let basisu = doc.raw(&format!("/textures/{t}/extensions/KHR_texture_basisu")).is_some();
    if image >= doc.root.images.len() {
        // A texture whose only source is an extension's (a `source` beside it is a fallback, used above).
        let msg = if basisu {
            format!("{KTX2_UNSUPPORTED}: {} (texture {t} has only a KHR_texture_basisu source)", slot.fallback())
        } else if doc.raw(&format!("/textures/{t}/source")).is_none() {
            format!(
                "texture {t} has no source image (extension-only sources such as EXT_texture_webp are not \
                 supported): {}",
                slot.fallback()
            )
        } else {
            format!("texture {t}: source image {image} does not exist: {}", slot.fallback())
        };
        warnings.push(pointer, msg);
        return None;
    }
    if is_ktx2(doc, image) {
        let uri = doc.root.images[image].uri.as_deref().map(|u| format!(" {}", shorten(u))).unwrap_or_default();
        warnings.push(pointer, format!("{KTX2_UNSUPPORTED}: {} (texture {t}, image {image}{uri})", slot.fallback()));
        return None;
    }
    if let Some(&loaded) = cache.loaded.get(&(image, encoding)) {
        return loaded;
    }
    let loaded = load_texture_image(doc, image, encoding, warnings).map(|img| {
        cache.images.push(Arc::new(img));
        cache.images.len() - 1
    });
    cache.loaded.insert((image, encoding), loaded);
    loaded
}

/// Decodes glTF image `index` (a file, a data: URI or a buffer view) into linear RGB; `None` with a warning that
/// names the file when it cannot.
fn load_texture_image(doc: &Doc, index: usize, encoding: Encoding, warnings: &mut Warnings) -> Option<RgbImage> {
    let pointer = format!("/images/{index}");
    let image = &doc.root.images[index];
    let declared_mime = image.mime_type.as_ref().map(|m| m.0.to_ascii_lowercase());
    let fallback = "material keeps its factors";
    let (bytes, hint, name) = match (&image.uri, image.buffer_view) {
        (Some(uri), _) => match resolve_uri(uri, doc.base_dir) {
            Ok(UriTarget::Data { bytes, mime }) => {
                (bytes, declared_mime.unwrap_or(mime), format!("{pointer} (data: URI)"))
            }
            Ok(UriTarget::File(path)) => {
                let name = path.display().to_string();
                let hint = extension_hint(&path).or(declared_mime).unwrap_or_default();
                if ImageFormat::from_hint(&hint).is_none() {
                    warnings.push(&pointer, format!("{name}: unsupported image type {hint:?}; {fallback}"));
                    return None;
                }
                match std::fs::read(&path) {
                    Ok(bytes) => {
                        doc.inputs.borrow_mut().push(crate::provenance::InputFile::read(&path, &bytes));
                        (bytes, hint, name)
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                        warnings.push(&pointer, format!("{name}: file not found; {fallback}"));
                        return None;
                    }
                    Err(e) => {
                        warnings.push(&pointer, format!("{name}: cannot read: {e}; {fallback}"));
                        return None;
                    }
                }
            }
            Err(msg) => {
                warnings.push(&pointer, format!("image {}: {msg}; {fallback}", shorten(uri)));
                return None;
            }
        },
        (None, Some(view)) => match view_bytes(doc, view.value()) {
            Ok((bytes, _)) => (bytes.to_vec(), declared_mime.unwrap_or_default(), format!("{pointer} (bufferView)")),
            Err(e) => {
                warnings.push(&pointer, format!("{e}; {fallback}"));
                return None;
            }
        },
        (None, None) => {
            warnings.push(&pointer, format!("neither uri nor bufferView; {fallback}"));
            return None;
        }
    };
    let Some(format) = ImageFormat::from_hint(&hint) else {
        warnings.push(&pointer, format!("{name}: unsupported image type {hint:?} (PNG and JPEG are read); {fallback}"));
        return None;
    };
    match load_image_from_bytes(&bytes, &hint, &name) {
        Ok(loaded) => {
            for w in loaded.warnings {
                warnings.push(&pointer, w);
            }
            let mut img = loaded.image;
            // The image module decodes 8/16-bit PNG and JPEG as sRGB; data textures hold linear values, so undo it.
            if encoding == Encoding::Linear && matches!(format, ImageFormat::Png | ImageFormat::Jpeg) {
                let encode = |c: f32| srgb_encode(c as f64) as f32;
                img.pixels.iter_mut().for_each(|p| *p = Vec3::new(encode(p.x), encode(p.y), encode(p.z)));
            }
            Some(img)
        }
        Err(e) => {
            warnings.push(&pointer, format!("{e}; {fallback}"));
            None
        }
    }
}

/// The file extension as a format hint, if it names a format kelvin reads.
fn extension_hint(path: &Path) -> Option<String> {
    let ext = path.extension()?.to_string_lossy().into_owned();
    ImageFormat::from_hint(&ext).map(|_| ext)
}
