//! Lights: KHR_lights_punctual and EXT_lights_ies, read from the raw JSON so that one malformed light is dropped
//! with a warning instead of failing the document. The policy per validator case is in the module docs of
//! [`super`].

use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
use std::sync::Arc;

use glam::{Affine3A, Vec3};
use serde_json::{Map, Value};

use super::accessor::view_bytes;
use super::container::{UriTarget, resolve_uri, shorten};
use super::{Doc, IesSource, LightData, LightKind, Warnings};

const PUNCTUAL: &str = "KHR_lights_punctual";
const IES: &str = "EXT_lights_ies";
/// The media type EXT_lights_ies requires for profiles in buffer views.
const IES_MIME: &str = "application/x-ies-lm-63";

/// The KHR_lights_punctual objects taken out of the JSON before `gltf::json` sees it.
pub(super) struct RawLights {
    /// `extensions.KHR_lights_punctual` of the root.
    root: Option<Value>,
    /// `nodes[i].extensions.KHR_lights_punctual`, by node index.
    nodes: HashMap<usize, Value>,
}

/// Removes the KHR_lights_punctual objects from the root and the nodes (one malformed light would otherwise
/// make `gltf::json` reject the whole document).
pub(super) fn take_punctual(json: &mut Value) -> RawLights {
    let take = |v: &mut Value| v.get_mut("extensions").and_then(Value::as_object_mut).and_then(|e| e.remove(PUNCTUAL));
    let root = take(json);
    let mut nodes = HashMap::new();
    if let Some(list) = json.get_mut("nodes").and_then(Value::as_array_mut) {
        for (i, node) in list.iter_mut().enumerate() {
            if let Some(ext) = take(node) {
                nodes.insert(i, ext);
            }
        }
    }
    RawLights { root, nodes }
}

/// Light definitions (not yet placed) and the node references to them.
pub(super) struct LightTable {
    /// KHR_lights_punctual lights in file order; `None` for dropped ones. `world` is the identity here.
    punctual: Vec<Option<LightData>>,
    /// Whether the root KHR_lights_punctual object exists.
    punctual_defined: bool,
    node_refs: HashMap<usize, Value>,
    /// EXT_lights_ies profiles in file order; `None` for unusable ones.
    profiles: Vec<Option<IesSource>>,
}

impl LightTable {
    pub(super) fn new(doc: &Doc, raw: RawLights, warnings: &mut Warnings) -> Self {
        let root_pointer = format!("/extensions/{PUNCTUAL}");
        let mut punctual = Vec::new();
        if let Some(root) = &raw.root {
            match root.get("lights") {
                None => warnings.push(&root_pointer, "'lights' must be defined; no lights"),
                Some(Value::Array(list)) if list.is_empty() => {
                    warnings.push(&format!("{root_pointer}/lights"), "empty array; no lights")
                }
                Some(Value::Array(list)) => {
                    for (i, light) in list.iter().enumerate() {
                        punctual.push(parse_punctual(light, &format!("{root_pointer}/lights/{i}"), warnings));
                    }
                }
                Some(_) => warnings.push(&format!("{root_pointer}/lights"), "not an array; no lights"),
            }
        }
        if let Some(scenes) = doc.json.get("scenes").and_then(Value::as_array) {
            for i in (0..scenes.len()).filter(|i| doc.raw(&format!("/scenes/{i}/extensions/{PUNCTUAL}")).is_some()) {
                warnings.push(&format!("/scenes/{i}/extensions/{PUNCTUAL}"), "lights belong on nodes; ignored here");
            }
        }
        let profiles = match doc.raw(&format!("/extensions/{IES}/lights")).and_then(Value::as_array) {
            Some(list) => list.iter().enumerate().map(|(i, p)| ies_profile(doc, i, p, warnings)).collect(),
            None => Vec::new(),
        };
        Self { punctual, punctual_defined: raw.root.is_some(), node_refs: raw.nodes, profiles }
    }

    /// The lights attached to node `node`, placed at `world`; unresolved references are dropped with a warning.
    pub(super) fn at_node(
        &self,
        doc: &Doc,
        node: usize,
        node_name: Option<&str>,
        world: Affine3A,
        warnings: &mut Warnings,
    ) -> Vec<LightData> {
        let mut out = Vec::new();
        if let Some(reference) = self.node_refs.get(&node) {
            let pointer = format!("/nodes/{node}/extensions/{PUNCTUAL}");
            // The validator reports a missing root extension at the node's object (a failed dependency), beside
            // any error in the reference itself.
            if !self.punctual_defined {
                let light = reference.get("light").map_or(String::new(), |l| format!(" (light {l})"));
                warnings.push(
                    &pointer,
                    format!("the root {PUNCTUAL} extension must be defined; reference{light} unresolved, dropped"),
                );
            }
            match reference.get("light").map(|l| (l, l.as_u64())) {
                None => warnings.push(&pointer, "'light' must be defined; reference dropped"),
                Some((l, None)) => warnings.push(&format!("{pointer}/light"), format!("{l} is not a light index")),
                Some((_, Some(_))) if !self.punctual_defined => {} // dropped above
                Some((_, Some(i))) => match self.punctual.get(i as usize) {
                    None => warnings.push(
                        &format!("{pointer}/light"),
                        format!("light {i} unresolved ({} defined); reference dropped", self.punctual.len()),
                    ),
                    Some(None) => {
                        warnings.push(&format!("{pointer}/light"), format!("light {i} was dropped (see above)"))
                    }
                    Some(Some(light)) => out.push(light.clone()),
                },
            }
        }
        let ies_pointer = format!("/nodes/{node}/extensions/{IES}");
        if let Some(reference) = doc.raw(&ies_pointer)
            && let Some(light) = self.ies_instance(reference, &ies_pointer, warnings)
        {
            out.push(light);
        }
        for light in &mut out {
            light.world = world;
            light.node = Some(node);
            light.node_name = node_name.map(str::to_string);
        }
        out
    }

    /// An EXT_lights_ies node reference: `{ light, multiplier = 1, color = [1, 1, 1] }`.
    fn ies_instance(&self, reference: &Value, pointer: &str, warnings: &mut Warnings) -> Option<LightData> {
        let Some(obj) = reference.as_object() else {
            warnings.push(pointer, "not an object; ignored");
            return None;
        };
        let Some(i) = obj.get("light").and_then(Value::as_u64) else {
            warnings.push(pointer, "'light' must be a light index; reference dropped");
            return None;
        };
        let Some(source) = self.profiles.get(i as usize) else {
            warnings.push(
                &format!("{pointer}/light"),
                format!("IES light {i} unresolved ({} defined); reference dropped", self.profiles.len()),
            );
            return None;
        };
        let source = source.clone()?; // dropped with a warning already
        let mut multiplier = number(obj, "multiplier", 1.0, pointer, warnings);
        if !(multiplier.is_finite() && multiplier >= 0.0) {
            warnings.push(&format!("{pointer}/multiplier"), format!("{multiplier} is not a finite value >= 0; 0 used"));
            multiplier = 0.0;
        }
        Some(LightData {
            kind: LightKind::Ies,
            color: color(obj, pointer, warnings),
            intensity: multiplier,
            range: None,
            world: Affine3A::IDENTITY,
            name: None,
            node: None,
            node_name: None,
            ies: Some(source),
        })
    }
}

/// One KHR_lights_punctual light definition; `None` (with a warning) when it cannot be used.
fn parse_punctual(light: &Value, pointer: &str, warnings: &mut Warnings) -> Option<LightData> {
    let Some(obj) = light.as_object() else {
        warnings.push(pointer, "not an object; light dropped");
        return None;
    };
    let kind = match obj.get("type").map(|t| (t, t.as_str())) {
        None => {
            warnings.push(pointer, "'type' must be defined; light dropped");
            return None;
        }
        Some((_, Some("point"))) => LightKind::Point,
        Some((_, Some("directional"))) => LightKind::Directional,
        Some((_, Some("spot"))) => spot_angles(obj, pointer, warnings),
        Some((t, _)) => {
            warnings.push(
                &format!("{pointer}/type"),
                format!("invalid value {t}; valid values are 'directional', 'point', 'spot'; light dropped"),
            );
            return None;
        }
    };
    if !matches!(kind, LightKind::Spot { .. }) && obj.contains_key("spot") {
        warnings.push(&format!("{pointer}/spot"), "spot is ignored for a light that is not a spot light");
    }
    let mut intensity = number(obj, "intensity", 1.0, pointer, warnings);
    if !(intensity.is_finite() && intensity >= 0.0) {
        warnings.push(&format!("{pointer}/intensity"), format!("{intensity} is not a finite value >= 0; 0 used"));
        intensity = 0.0;
    }
    let range = match obj.get("range") {
        None => None,
        Some(_) if kind == LightKind::Directional => {
            warnings.push(&format!("{pointer}/range"), "range is ignored for directional lights");
            None
        }
        Some(_) => Some(number(obj, "range", 0.0, pointer, warnings)).filter(|&r| {
            let ok = r.is_finite() && r > 0.0;
            if !ok {
                warnings.push(&format!("{pointer}/range"), format!("{r} is not a finite value > 0; range ignored"));
            }
            ok
        }),
    };
    Some(LightData {
        kind,
        color: color(obj, pointer, warnings),
        intensity,
        range,
        world: Affine3A::IDENTITY,
        name: obj.get("name").and_then(Value::as_str).map(str::to_string),
        node: None,
        node_name: None,
        ies: None,
    })
}

/// Spot cone half-angles made to satisfy 0 <= inner <= outer <= pi/2, outer > 0. KHR_lights_punctual asks for
/// inner < outer; when not, inner is set to outer (a hard-edged cone).
fn spot_angles(obj: &Map<String, Value>, pointer: &str, warnings: &mut Warnings) -> LightKind {
    let spot_pointer = format!("{pointer}/spot");
    let empty = Map::new();
    let defaults = "glTF defaults used (inner 0, outer pi/4)";
    // A missing property is reported at its parent object (as the validator does), a bad one at itself.
    let spot = match obj.get("spot") {
        Some(Value::Object(spot)) => spot,
        Some(_) => {
            warnings.push(&spot_pointer, format!("is not an object; {defaults}"));
            &empty
        }
        None => {
            warnings.push(pointer, format!("'spot' must be defined for a spot light; {defaults}"));
            &empty
        }
    };
    let mut inner = number(spot, "innerConeAngle", 0.0, &spot_pointer, warnings);
    let mut outer = number(spot, "outerConeAngle", FRAC_PI_4, &spot_pointer, warnings);
    if !(outer > 0.0 && outer <= FRAC_PI_2) {
        let fixed = if outer > FRAC_PI_2 { FRAC_PI_2 } else { FRAC_PI_4 };
        warnings.push(&format!("{spot_pointer}/outerConeAngle"), format!("{outer} is outside (0, pi/2]; {fixed} used"));
        outer = fixed;
    }
    if inner.is_nan() || inner < 0.0 {
        warnings.push(&format!("{spot_pointer}/innerConeAngle"), format!("{inner} is negative; 0 used"));
        inner = 0.0;
    }
    if outer <= inner {
        warnings.push(
            &format!("{spot_pointer}/outerConeAngle"),
            format!(
                "outerConeAngle ({outer}) is less than or equal to innerConeAngle ({inner}); innerConeAngle set to \
                 {outer} (hard-edged cone)"
            ),
        );
        inner = outer;
    }
    LightKind::Spot { inner_cone_angle: inner, outer_cone_angle: outer }
}

/// `obj[key]` as f32, `default` when absent; a non-number gives a warning and the default.
fn number(obj: &Map<String, Value>, key: &str, default: f32, pointer: &str, warnings: &mut Warnings) -> f32 {
    match obj.get(key) {
        None => default,
        Some(v) => match v.as_f64() {
            Some(x) => x as f32,
            None => {
                warnings.push(&format!("{pointer}/{key}"), format!("{v} is not a number; {default} used"));
                default
            }
        },
    }
}

/// `obj.color` as linear RGB in [0, 1], white when absent; bad values are clamped or defaulted with a warning.
fn color(obj: &Map<String, Value>, pointer: &str, warnings: &mut Warnings) -> Vec3 {
    let Some(value) = obj.get("color") else { return Vec3::ONE };
    let parsed = value.as_array().filter(|a| a.len() == 3).and_then(|a| {
        let c: Option<Vec<f32>> = a.iter().map(|x| x.as_f64().map(|x| x as f32)).collect();
        c.map(|c| Vec3::new(c[0], c[1], c[2]))
    });
    let Some(c) = parsed else {
        warnings.push(&format!("{pointer}/color"), format!("{value} is not 3 numbers; white used"));
        return Vec3::ONE;
    };
    let clamped = c.clamp(Vec3::ZERO, Vec3::ONE);
    if clamped != c {
        warnings.push(&format!("{pointer}/color"), format!("{c} is outside [0, 1]; clamped to {clamped}"));
    }
    clamped
}

/// An EXT_lights_ies profile: an external file (which must exist), a data: URI or a buffer view.
fn ies_profile(doc: &Doc, index: usize, profile: &Value, warnings: &mut Warnings) -> Option<IesSource> {
    let pointer = format!("/extensions/{IES}/lights/{index}");
    let uri = profile.get("uri").and_then(Value::as_str);
    let view = profile.get("bufferView").and_then(Value::as_u64);
    let mime = profile.get("mimeType").and_then(Value::as_str);
    match (uri, view) {
        (Some(uri), _) => match resolve_uri(uri, doc.base_dir) {
            Ok(UriTarget::Data { bytes, .. }) => {
                Some(IesSource::Embedded { bytes: Arc::from(bytes), what: format!("{} {pointer}", doc.what) })
            }
            Ok(UriTarget::File(path)) if path.is_file() => Some(IesSource::File(path)),
            Ok(UriTarget::File(path)) => {
                warnings.push(&pointer, format!("{}: IES profile not found; light dropped", path.display()));
                None
            }
            Err(msg) => {
                warnings.push(&pointer, format!("IES profile {}: {msg}; light dropped", shorten(uri)));
                None
            }
        },
        (None, Some(view)) => {
            if mime != Some(IES_MIME) {
                warnings.push(&format!("{pointer}/mimeType"), format!("should be {IES_MIME:?}; read as IES anyway"));
            }
            match view_bytes(doc, view as usize) {
                Ok((bytes, _)) => Some(IesSource::Embedded {
                    bytes: Arc::from(bytes),
                    what: format!("{} bufferView {view}", doc.what),
                }),
                Err(e) => {
                    warnings.push(&pointer, format!("{e}; light dropped"));
                    None
                }
            }
        }
        (None, None) => {
            warnings.push(&pointer, "neither uri nor bufferView; light dropped");
            None
        }
    }
}
