//! Closed forms from the files' light data: the irradiance the light system delivers at chosen
//! points against the files' punctual lights (and the Cornell box's emissive quad).

use glam::{DQuat, DVec3, Vec3};
use kelvin::geometry::{GeometryId, Hit, Ray, SceneBvh};
use kelvin::light::LightTable;
use kelvin::shading::{DirectLighting, LightSelection, Settings, ShadingBatch};

use super::{Loaded, load};
use crate::common;
use crate::common::{Stats, lum};

/// A KHR_lights_punctual light as its file gives it: the light object and its node's TRS (every
/// light node below is a root node, so its TRS is its world transform).
struct FileLight {
    name: &'static str,
    kind: Kind,
    /// cd (point, spot) or lx (directional).
    intensity: f64,
    color: [f64; 3],
    translation: [f64; 3],
    /// Node rotation quaternion (x, y, z, w).
    rotation: [f64; 4],
}

#[derive(Clone, Copy)]
enum Kind {
    Point,
    /// innerConeAngle, outerConeAngle (radians).
    Spot(f64, f64),
    Directional,
}

const WHITE: [f64; 3] = [1.0, 1.0, 1.0];

impl FileLight {
    fn position(&self) -> DVec3 {
        DVec3::from(self.translation)
    }
    /// glTF lights shine along the node's local -Z axis.
    fn forward(&self) -> DVec3 {
        (DQuat::from_array(self.rotation).normalize() * DVec3::NEG_Z).normalize()
    }
    /// Luminous intensity (cd) or illuminance (lx): the intensity times the colour's luminance.
    fn luminous(&self) -> f64 {
        let [r, g, b] = self.color;
        self.intensity * (0.2126 * r + 0.7152 * g + 0.0722 * b)
    }
    /// Irradiance (lx) at `p` on a surface with unit normal `n`, without occlusion.
    fn irradiance(&self, p: DVec3, n: DVec3) -> f64 {
        match self.kind {
            Kind::Directional => self.luminous() * n.dot(-self.forward()).max(0.0),
            Kind::Point | Kind::Spot(..) => {
                let d = self.position() - p;
                let wi = d.normalize();
                let falloff = match self.kind {
                    Kind::Spot(inner, outer) => smooth_step(-wi.dot(self.forward()), outer.cos(), inner.cos()),
                    _ => 1.0,
                };
                self.luminous() * falloff * n.dot(wi).max(0.0) / d.length_squared()
            }
        }
    }
}

/// kelvin's spot falloff (pbrt-v4): the cubic smoothstep of cos(theta) between cos(outer) and
/// cos(inner).
fn smooth_step(x: f64, a: f64, b: f64) -> f64 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

pub(super) fn lum_rgb(p: Vec3) -> f64 {
    0.2126 * p.x as f64 + 0.7152 * p.y as f64 + 0.0722 * p.z as f64
}

/// A point to light: on a surface hit (`geometry` set, so its shadow rays pass its own flat
/// triangle) or in free space.
struct Receiver {
    p: Vec3,
    p_error: Option<Vec3>,
    /// Unit normal, turned toward the side the lights are checked from.
    n: Vec3,
    geometry: GeometryId,
}

impl Receiver {
    fn free(p: Vec3, n: Vec3) -> Self {
        Self { p, p_error: None, n: n.normalize(), geometry: GeometryId::NONE }
    }
    fn on(hit: &Hit, toward: Vec3) -> Self {
        let n = if hit.ng.dot(toward) < 0.0 { -hit.ng } else { hit.ng };
        Self { p: hit.p, p_error: Some(hit.p_error), n, geometry: hit.id }
    }
}

impl Loaded {
    /// Brings the BVH and the light table up to date, in all-lights mode with `spp` samples per
    /// light and shadows on.
    fn prepare(&mut self, spp: u32) {
        *self.world.resource_mut::<Settings>() =
            Settings { selection: LightSelection::All, samples_per_point: spp, shadows: true, ..Default::default() };
        self.world.resource_mut::<ShadingBatch>().clear();
        self.schedule.run(&mut self.world);
    }

    /// The first surface hit on the ray from `from` through `target`, asserted to lie within `tol`
    /// of `target`: a point of the file's geometry, and the first thing seen from `from`.
    fn surface(&self, from: Vec3, target: Vec3, tol: f32, what: &str) -> Hit {
        let bvh = self.world.resource::<SceneBvh>();
        let hit = bvh.closest_hit(&Ray::new(from, target - from)).unwrap_or_else(|| panic!("{what}: ray hit nothing"));
        assert!((hit.p - target).length() <= tol, "{what}: first hit {} is not at {target}", hit.p);
        hit
    }

    /// The light system's entries for one receiver: (luminance of radiance, wi, pdf, delta).
    fn entries(&mut self, r: &Receiver) -> Vec<(f64, Vec3, f32, bool)> {
        {
            let mut batch = self.world.resource_mut::<ShadingBatch>();
            batch.clear();
            match r.p_error {
                Some(err) => batch.push_with_error(r.p, err, r.n, r.n, 0, 0),
                None => batch.push(r.p, r.n, 0, 0),
            }
            if r.geometry != GeometryId::NONE {
                batch.geometry = vec![r.geometry];
            }
        }
        self.schedule.run(&mut self.world);
        let lighting = self.world.resource::<DirectLighting>();
        lighting
            .entries(0)
            .map(|e| (lum(lighting.radiance[e]), lighting.wi[e], lighting.pdf[e], lighting.delta[e]))
            .collect()
    }

    /// Irradiance (lx) from the delta lights at `r`: sum of L cos / pdf over its entries, one per
    /// light (pdf 1 in all-lights mode).
    fn delta_irradiance(&mut self, r: &Receiver, lights: usize, what: &str) -> f64 {
        let entries = self.entries(r);
        assert_eq!(entries.len(), lights, "{what}: one entry per light of the file");
        entries
            .iter()
            .map(|&(l, wi, pdf, delta)| {
                // A failed sample (outside a spot's cone) is an empty entry: pdf 0, not marked delta.
                assert!(delta || (pdf == 0.0 && l == 0.0), "{what}: a non-delta light");
                if pdf > 0.0 { l * r.n.dot(wi).max(0.0) as f64 / pdf as f64 } else { 0.0 }
            })
            .sum()
    }
}

/// Asserts `measured` is within 1e-4 (relative) of `expected`; an expected 0 must be met
/// exactly up to 1e-9 lx.
fn assert_close(what: &str, measured: f64, expected: f64) {
    let rel = (measured - expected).abs() / expected.abs().max(1e-300);
    eprintln!("{what}: E = {measured:.6} lx, closed form {expected:.6} lx, rel err {rel:.2e}");
    if expected == 0.0 {
        assert!(measured.abs() < 1e-9, "{what}: {measured} lx where no light reaches");
    } else {
        assert!(rel < 1e-4, "{what}: {measured} lx vs {expected} lx");
    }
}

fn vec(p: DVec3) -> Vec3 {
    p.as_vec3()
}

/// Every renderling spot light's intensity (cd): 54351.41306588226 in the files.
const SPOT_CD: f64 = 54351.41306588226;

/// The 4 spot lights of four_spotlights.glb: all at (0, 1, 0), cones 0.556 / 0.654 rad. The node
/// names do not match their aims: "light_negative_z" shines down (-Y), "light_positive_z" up
/// (+Y), "light_positive_x" along +X and "light_positive_y" along -Z. There is no mesh, so
/// nothing shadows: the points below are in free space.
#[test]
fn four_spotlights_glb_four_spots_in_free_space() {
    let cone = Kind::Spot(0.556323685321221, 0.6544984579086304);
    let light = |name, rotation| FileLight {
        name,
        kind: cone,
        intensity: SPOT_CD,
        color: WHITE,
        translation: [0.0, 1.0, 0.0],
        rotation,
    };
    let lights = [
        light("light_negative_z", [-0.7071068286895752, 0.0, 0.0, 0.7071068286895752]),
        light("light_positive_z", [0.70710688829422, 0.0, 0.0, 0.7071066498756409]),
        light("light_positive_x", [0.0, -0.7071068286895752, 0.0, 0.7071068286895752]),
        light("light_positive_y", [0.0, 0.0, 0.0, 1.0]),
    ];
    let mut scene = load("renderling/four_spotlights.glb");
    scene.prepare(1);
    let origin = DVec3::new(0.0, 1.0, 0.0);
    // theta = 0.6 rad off light_positive_x's axis, in its falloff band (0.556 .. 0.654), 2 m away,
    // on a surface facing -X (so cos = cos 0.6); 55 degrees off light_positive_y's -Z axis and 90
    // off the others, outside their cones.
    let band = origin + 2.0 * DVec3::new(0.6f64.cos(), 0.0, 0.6f64.sin());
    let cases = [
        ("(0, 0, 0) facing up, on light_negative_z's axis 1 m below: E = I", DVec3::ZERO, DVec3::Y),
        ("0.6 rad off light_positive_x's axis, in its falloff band", band, DVec3::NEG_X),
        // Straight along -X from the lights: behind light_positive_x, 90 degrees off the rest.
        ("(-2, 1, 0) facing +X, where no cone reaches", DVec3::new(-2.0, 1.0, 0.0), DVec3::X),
    ];
    for (what, p, n) in cases {
        let expected: f64 = lights.iter().map(|l| l.irradiance(p, n)).sum();
        let measured = scene.delta_irradiance(&Receiver::free(vec(p), vec(n)), lights.len(), what);
        assert_close(&format!("four_spotlights.glb, {what}"), measured, expected);
    }
    // The first case's closed form is the on-axis intensity itself; the second is within the band.
    assert!((lights[0].irradiance(DVec3::ZERO, DVec3::Y) - SPOT_CD).abs() < 1e-6 * SPOT_CD);
    let f = lights[2].irradiance(band, DVec3::NEG_X) / (SPOT_CD * 0.6f64.cos() / 4.0);
    assert!(f > 0.05 && f < 0.95, "falloff {f} should be inside the band");
}

/// spot_one.glb: one spot light "Light" at (0, 1, 0) aiming down (-Y), cones 0.271 / 0.543 rad,
/// over a floor at y = 0 with four short pillars (height 0.181), one right under the light.
#[test]
fn spot_one_glb_spot_on_the_pillar_and_in_its_falloff_band() {
    let light = FileLight {
        name: "Light",
        kind: Kind::Spot(0.2713986933231354, 0.5427973866462708),
        intensity: SPOT_CD,
        color: WHITE,
        translation: [0.0, 1.0, 0.0],
        rotation: [-0.7071068286895752, 0.0, 0.0, 0.7071068286895752],
    };
    let mut scene = load("renderling/spot_one.glb");
    scene.prepare(1);
    let cases = [
        // The top of the pillar under the light (Cylinder, 0.1808 tall): on the axis, 0.819 m.
        ("top of the pillar under the light, on the axis", Vec3::new(0.0, 0.1807605, 0.0)),
        // A floor point 0.40 rad off the axis (falloff band 0.271 .. 0.543), away from the
        // pillars (at x = 0 .. 1, z = 0 and (0.5, -0.5)): the segment to the light is clear.
        ("floor at (-0.3, 0, 0.3), in the falloff band", Vec3::new(-0.3, 0.0, 0.3)),
    ];
    for (what, target) in cases {
        // The first hit on the ray from the light through the target is the target: lit.
        let hit = scene.surface(vec(light.position()), target, 1e-4, what);
        let r = Receiver::on(&hit, vec(light.position()) - hit.p);
        let expected = light.irradiance(r.p.as_dvec3(), r.n.as_dvec3());
        let measured = scene.delta_irradiance(&r, 1, what);
        assert_close(&format!("spot_one.glb, {what}"), measured, expected);
    }
}

/// spot_lights.glb: two narrow spot lights (cones 0.077 / 0.091 rad) aimed at the one cube
/// (-1 .. 1 on each axis): "Light" from above onto its top face, "Light.001" along -X onto its
/// +X face. Each axis point is lit by its own light only (the other's cone is far away).
#[test]
fn spot_lights_glb_two_narrow_spots_each_on_its_cube_face() {
    let cone = Kind::Spot(0.07714356129910271, 0.09075713157653809);
    let lights = [
        FileLight {
            name: "Light",
            kind: cone,
            intensity: SPOT_CD,
            color: WHITE,
            translation: [3.53645658493042, 5.903861999511719, -1.3921775817871094],
            rotation: [-0.28416627645492554, 0.7269423007965088, 0.34203392267227173, 0.5232754945755005],
        },
        FileLight {
            name: "Light.001",
            kind: cone,
            intensity: SPOT_CD,
            color: WHITE,
            translation: [4.2837934494018555, -0.00579911470413208, 0.00030934810638427734],
            rotation: [-0.5000000596046448, 0.5, -0.5, 0.5],
        },
    ];
    let mut scene = load("renderling/spot_lights.glb");
    scene.prepare(1);
    // Where each axis meets its face: the top (y = 1) for "Light", x = 1 for "Light.001".
    let faces = [(DVec3::Y, "top face y = 1"), (DVec3::X, "+X face x = 1")];
    for (light, (axis, face)) in lights.iter().zip(faces) {
        let (o, f) = (light.position(), light.forward());
        let t = (o.dot(axis) - 1.0) / -f.dot(axis);
        let target = o + t * f;
        let what = format!("{} on its axis at the cube's {face}", light.name);
        let hit = scene.surface(vec(o), vec(target), 1e-4, &what);
        let r = Receiver::on(&hit, vec(o) - hit.p);
        let (p, n) = (r.p.as_dvec3(), r.n.as_dvec3());
        let expected: f64 = lights.iter().map(|l| l.irradiance(p, n)).sum();
        assert!((expected - light.irradiance(p, n)).abs() < 1e-9 * expected, "the other spot reaches {what}");
        let measured = scene.delta_irradiance(&r, 2, &what);
        assert_close(&format!("spot_lights.glb, {what}"), measured, expected);
    }
}

/// shadow_mapping_spots.glb: spot "Light" (cones 0.067 / 0.654 rad: a wide falloff band) and spot
/// "Light.001" (0.365 / 0.429 rad) over a floor slab (top y = 0.1143) with a cone and Suzanne.
#[test]
fn shadow_mapping_spots_glb_wide_falloff_spot_on_the_floor() {
    let lights = [
        FileLight {
            name: "Light",
            kind: Kind::Spot(0.0674851900246054, 0.6544984579086304),
            intensity: SPOT_CD,
            color: WHITE,
            translation: [7.437812805175781, 5.903861999511719, -7.430910587310791],
            rotation: [-0.1504562944173813, 0.8709462881088257, 0.27162763476371765, 0.3808331787586212],
        },
        FileLight {
            name: "Light.001",
            kind: Kind::Spot(0.36494834912210106, 0.42935100197792053),
            intensity: SPOT_CD,
            color: WHITE,
            translation: [7.120790481567383, 6.983683109283447, 5.674097537994385],
            rotation: [-0.4061186611652374, 0.4206234812736511, 0.181122288107872, 0.7907833456993103],
        },
    ];
    let mut scene = load("renderling/shadow_mapping_spots.glb");
    scene.prepare(1);
    // Floor point (1, 0.1143, -4): 0.226 rad off "Light"'s axis (inside its falloff band), and
    // 0.504 rad off "Light.001"'s (outside its 0.429 cone). The segment to "Light" stays at
    // z < -4, clear of the cone (z > -1.33) and Suzanne (z > 2.1).
    let what = "floor (1, 0.114, -4) in Light's falloff band";
    let target = Vec3::new(1.0, 0.11433935, -4.0);
    let hit = scene.surface(vec(lights[0].position()), target, 1e-4, what);
    let r = Receiver::on(&hit, vec(lights[0].position()) - hit.p);
    let (p, n) = (r.p.as_dvec3(), r.n.as_dvec3());
    assert_eq!(lights[1].irradiance(p, n), 0.0, "Light.001's cone reaches the point");
    let expected = lights[0].irradiance(p, n);
    let measured = scene.delta_irradiance(&r, 2, what);
    assert_close(&format!("shadow_mapping_spots.glb, {what}"), measured, expected);
}

/// shadow_mapping_point.glb: point light "Light" (5435.14 cd) at (0, 0.5, 0) over a floor slab
/// (top y = 0.1234) with two pillars and some 3D text.
#[test]
fn shadow_mapping_point_glb_point_light_on_the_floor() {
    let light = FileLight {
        name: "Light",
        kind: Kind::Point,
        intensity: 5435.141306588225,
        color: WHITE,
        translation: [0.0, 0.5, 0.0],
        rotation: [-0.28416627645492554, 0.7269423007965088, 0.34203392267227173, 0.5232754945755005],
    };
    let mut scene = load("renderling/shadow_mapping_point.glb");
    scene.prepare(1);
    let floor = 0.12340379;
    let cases = [
        ("floor right under the light", Vec3::new(0.0, floor, 0.0)),
        // The diagonal x = z misses the pillars (x or z near 0) and the text (|z| < 0.36 where
        // |x| > 0.8; z near -1 where x > -0.74).
        ("floor at (-2, 0.123, -2), grazing", Vec3::new(-2.0, floor, -2.0)),
    ];
    for (what, target) in cases {
        let hit = scene.surface(vec(light.position()), target, 1e-4, what);
        let r = Receiver::on(&hit, vec(light.position()) - hit.p);
        let expected = light.irradiance(r.p.as_dvec3(), r.n.as_dvec3());
        let measured = scene.delta_irradiance(&r, 1, what);
        assert_close(
            &format!("shadow_mapping_point.glb, {light_name}: {what}", light_name = light.name),
            measured,
            expected,
        );
    }
}

/// shadow_mapping_points.glb: four point lights (2174.06 cd) at (+-1.5, 0.238, +-1.5), in the
/// gaps of a 3 x 3 grid of 2 m cubes (centres at 0 and +-3 on x and z, y from -1 to 1) standing on
/// a floor (top y = -1). Hard case: two of the four lights are shadowed at the first point.
#[test]
fn shadow_mapping_points_glb_four_point_lights_two_hidden_by_the_central_cube() {
    let light = |name, translation, rotation| FileLight {
        name,
        kind: Kind::Point,
        intensity: 2174.0565226352905,
        color: WHITE,
        translation,
        rotation,
    };
    let lights = [
        light("Point", [1.5, 0.23793458938598633, -1.5], [-0.7071068286895752, 0.0, 0.0, 0.7071068286895752]),
        light("Point.001", [-1.5, 0.23793457448482513, -1.4999998807907104], [-0.5, 0.5, 0.5, 0.5]),
        light(
            "Point.002",
            [-1.499999761581421, 0.23793455958366394, 1.5000001192092896],
            [0.0, -0.7071068286895752, -0.7071068286895752, 1.1520233300643667e-07],
        ),
        light(
            "Point.003",
            [1.500000238418579, 0.23793454468250275, 1.4999996423721313],
            [-0.5000001192092896, -0.49999988079071045, -0.49999988079071045, 0.5000001192092896],
        ),
    ];
    let mut scene = load("renderling/shadow_mapping_points.glb");
    scene.prepare(1);
    // (0, -1, 1.5): the floor in the corridor z = 1 .. 2 between the cubes. Point.002 and
    // Point.003 (z = 1.5) see it along the corridor; the segments from Point and Point.001
    // (z = -1.5) enter the central cube (its z = 1 face is crossed at x = +-0.25, y = -0.79, well
    // inside the face), so they are shadowed and left out of the sum.
    // (1, 0, 0): the central cube's +X face. Point and Point.003 (x = 1.5) face it with nothing
    // between; Point.001 and Point.002 are behind the face (cos < 0).
    let cases = [
        (
            "floor (0, -1, 1.5): Point, Point.001 hidden by the central cube",
            Vec3::new(0.0, -1.0, 1.5),
            3,
            [false, false, true, true],
        ),
        ("central cube's +X face at (1, 0, 0)", Vec3::new(1.0, 0.0, 0.0), 3, [true, true, true, true]),
    ];
    for (what, target, from, visible) in cases {
        let hit = scene.surface(vec(lights[from].position()), target, 1e-4, what);
        let r = Receiver::on(&hit, vec(lights[from].position()) - hit.p);
        let (p, n) = (r.p.as_dvec3(), r.n.as_dvec3());
        let unshadowed: f64 = lights.iter().map(|l| l.irradiance(p, n)).sum();
        let expected: f64 = lights.iter().zip(visible).filter(|(_, v)| *v).map(|(l, _)| l.irradiance(p, n)).sum();
        eprintln!("{what}: without shadows the closed form would be {unshadowed:.4} lx");
        let measured = scene.delta_irradiance(&r, 4, what);
        assert_close(&format!("shadow_mapping_points.glb, {what}"), measured, expected);
    }
}

/// Irradiance of a directional light at the first surfaces it meets on rays toward `targets`
/// (those points are lit by construction: nothing lies between them and the light's direction).
/// `tol` bounds how far from its target each first hit may be.
fn check_directional(file: &str, light: &FileLight, targets: &[(&str, Vec3, f32)]) {
    let mut scene = load(file);
    scene.prepare(1);
    let lights = scene.world.resource::<LightTable>().len();
    let to_light = -light.forward();
    for &(what, target, tol) in targets {
        // Farther than any of these scenes' extent.
        let from = target + vec(to_light) * 1000.0;
        let hit = scene.surface(from, target, tol, what);
        let r = Receiver::on(&hit, vec(to_light));
        let expected = light.irradiance(r.p.as_dvec3(), r.n.as_dvec3());
        assert!(expected > 0.1 * light.luminous(), "{file}, {what}: the point barely faces the light");
        let measured = scene.delta_irradiance(&r, lights, what);
        assert_close(&format!("{file}, {} ({} lx): {what}", light.name, light.intensity), measured, expected);
    }
}

/// cheetah_cone.glb: its directional light "Light" (68300 lx, shining along (0.81, -0.58, 0))
/// on an upside-down cone (base radius 1 at y = 1, apex at y = -1) and the sphere resting on it.
#[test]
fn cheetah_cone_glb_directional_light_on_sphere_and_cone() {
    let light = FileLight {
        name: "Light",
        kind: Kind::Directional,
        intensity: 68300.0,
        color: WHITE,
        translation: [3.2558979988098145, 5.708354949951172, 1.7806119918823242],
        rotation: [-0.6292962431907654, -0.322469025850296, 0.32246899604797363, 0.6292962431907654],
    };
    // The sphere's centre (0, 1.61, 0), radius 0.538: the lit side's first hit lies within 0.54
    // of it. The cone's side at y = 0 has radius 0.5: (-0.5, 0, 0) is on the side toward the
    // light (which comes from -X and above; the side leans outward, so cos is only 0.46), and the
    // sphere is above the cone's rim, out of the way.
    check_directional(
        "renderling/cheetah_cone.glb",
        &light,
        &[
            ("the sphere's lit side", Vec3::new(0.0, 1.6105, 0.0), 0.54),
            ("the cone's lit side", Vec3::new(-0.5, 0.0, 0.0), 1e-2),
        ],
    );
}

/// Coloured directional lights: kelvin's lux is the file's intensity times the colour's
/// luminance. VolumetricFogExample's "Sun" (68300 lx, colour (1, 0.9895, 0.8705): 67148 lx) on
/// the first surface toward the top of its building; light_tiling_test's "Light" (1366 lx, colour
/// (0.557, 0.646, 1): 892 lx) on its ground slab (top y = 1) at the origin; MixedLightingExample's
/// white "Sun" (2049 lx) on its floor (y = 0) at (1.2, 0, 1.2), away from the chair.
#[test]
fn directional_lights_of_bevy_and_light_tiling_files_at_their_lux() {
    let fog = FileLight {
        name: "Sun",
        kind: Kind::Directional,
        intensity: 68300.0,
        color: [1.0, 0.9894999861717224, 0.8705254793167114],
        translation: [4.382747650146484, 10.144035339355469, -0.30610767006874084],
        rotation: [-0.7003790140151978, 0.17756180465221405, -0.22268541157245636, 0.6544862985610962],
    };
    // Whatever the ray from the sun toward the middle of the building (bounds x +-3.2, y 0 .. 6.3,
    // z +-6.7) meets first, anywhere on it: that surface faces the sun unshadowed.
    check_directional(
        "bevy/VolumetricFogExample.glb",
        &fog,
        &[("the building's lit side", Vec3::new(0.0, 3.0, 0.0), 7.0)],
    );
    let tiling = FileLight {
        name: "Light",
        kind: Kind::Directional,
        intensity: 1366.0,
        color: [0.5569815039634705, 0.6462195515632629, 1.0],
        translation: [-1.8074493408203125, 99.7520523071289, 2.8426513671875],
        rotation: [-0.0901741236448288, -0.8744779825210571, -0.4119468629360199, 0.23970124125480652],
    };
    check_directional(
        "renderling/light_tiling_test.glb",
        &tiling,
        &[("ground at the origin", Vec3::new(0.0, 1.0, 0.0), 1e-3)],
    );
    let mixed = FileLight {
        name: "Sun",
        kind: Kind::Directional,
        intensity: 2049.0,
        color: WHITE,
        translation: [0.6279287338256836, 1.7347862720489502, 0.7396787405014038],
        rotation: [-0.48860564827919006, 0.11653755605220795, -0.20060963928699493, 0.8410941362380981],
    };
    check_directional(
        "bevy/MixedLightingExample/MixedLightingExample.gltf",
        &mixed,
        &[("floor at (1.2, 0, 1.2)", Vec3::new(1.2, 0.0, 1.2), 1e-3)],
    );
}

/// CornellBox.glb's emissive quad (node "Light": 130 x 105 at y = 547.913, emissive 100 cd/m^2,
/// double-sided) lighting the top of the tall box (y = 330): two area-light rows (its two
/// triangles), checked against Lambert's formula for the rectangle. Nothing lies between the box
/// top and the ceiling light.
#[test]
fn cornell_box_glb_emissive_quad_on_the_tall_box() {
    const SPP: u32 = 4096;
    let mut scene = load("bevy/CornellBox.glb");
    scene.prepare(SPP);
    let y = 547.91345;
    let quad = [
        Vec3::new(-343.0, y, -332.0),
        Vec3::new(-213.0, y, -332.0),
        Vec3::new(-213.0, y, -227.0),
        Vec3::new(-343.0, y, -227.0),
    ];
    // The quad's vertices as loaded (bounds of the area rows) are the rectangle above.
    {
        let table = scene.world.resource::<LightTable>();
        let (mut lo, mut hi) = (Vec3::MAX, Vec3::MIN);
        for row in &table.area().items {
            let (a, b) = row.light.shape.bounds();
            (lo, hi) = (lo.min(a), hi.max(b));
        }
        assert!(
            (lo - quad[0]).abs().max_element() < 1e-2 && (hi - quad[2]).abs().max_element() < 1e-2,
            "light at {lo} .. {hi}"
        );
    }
    // The tall box's top (bounds x -471 .. -265, z -454 .. -248) near its middle, from straight above.
    let what = "top of the tall box at (-368, 330, -351)";
    let target = Vec3::new(-368.0, 330.0, -351.0);
    let hit = scene.surface(target + Vec3::new(0.0, 150.0, 0.0), target, 1e-2, what);
    let r = Receiver::on(&hit, Vec3::Y);
    let entries = scene.entries(&r);
    assert_eq!(entries.len(), 2 * SPP as usize, "{what}: one entry per triangle and sample");
    // Entries run sample by sample, each with one entry per light row. A pdf carries all SPP
    // samples (`DirectLighting::pdf`): one sample's own estimate is its pair's sum times SPP.
    let mut stats = Stats::default();
    for pair in entries.chunks(2) {
        let one_sample = |&(l, wi, pdf, _): &(f64, Vec3, f32, bool)| {
            if pdf > 0.0 { l * r.n.dot(wi).max(0.0) as f64 / (pdf / SPP as f32) as f64 } else { 0.0 }
        };
        stats.add(pair.iter().map(one_sample).sum());
    }
    let expected = common::area::lambert(r.p, r.n, &quad, 100.0);
    stats.check(&format!("CornellBox.glb, {what}"), expected, 1e-4 * expected);
}
