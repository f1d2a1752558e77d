//! IES LM-63 parsing and the candela distribution: flux of real files versus an independent
//! integration, every symmetry case on synthetic files with closed-form flux, the A/B frames, old
//! formats, bad input (each error names its line), mutated files (no panics) and the CLI.

mod common;

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

use glam::Vec3;
use kelvin::rng::SplitMix64;
use kelvin::scene::ies::{IesError, IesProfile, IesVersion, PhotometricType, Symmetry, Tilt};

/// An index in 0..n from one f64 draw (so the mutation sequences stay as they were).
fn index_below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.f64() * n as f64) as usize % n.max(1)
}

/// A uniform direction on the sphere.
fn direction(rng: &mut SplitMix64) -> Vec3 {
    let z = 1.0 - 2.0 * rng.f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * rng.f64();
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}

/// Flux by a midpoint rule over (theta from -Z, phi) on an n_theta x 2 n_theta grid, through
/// `candela_dir` only: independent of the file's angles and of the closed-form cell integrals.
fn numeric_flux(p: &IesProfile, n_theta: usize) -> f64 {
    let n_phi = 2 * n_theta;
    let (dt, dp) = (PI / n_theta as f64, TAU / n_phi as f64);
    let mut total = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * dt;
        let (st, ct) = theta.sin_cos();
        let ring: f64 = (0..n_phi)
            .map(|j| {
                let (sp, cp) = ((j as f64 + 0.5) * dp).sin_cos();
                p.candela_dir(Vec3::new((st * cp) as f32, (st * sp) as f32, -ct as f32))
            })
            .sum();
        total += ring * st * dt * dp;
    }
    total
}

fn data_dir() -> PathBuf {
    common::files::test_data("ies")
}

fn real_files() -> Vec<PathBuf> {
    let dir = data_dir();
    let mut files = Vec::new();
    for sub in std::fs::read_dir(&dir).unwrap().flatten() {
        for f in std::fs::read_dir(sub.path()).into_iter().flatten().flatten() {
            if f.path().extension().is_some_and(|e| e.eq_ignore_ascii_case("ies")) {
                files.push(f.path());
            }
        }
    }
    files.sort();
    files
}

fn steps(a: f64, b: f64, step: f64) -> Vec<f64> {
    let n = ((b - a) / step).round() as usize;
    (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect()
}

fn join(xs: impl IntoIterator<Item = f64>) -> String {
    xs.into_iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(" ")
}

/// An LM-63-2002 file with one numeric record per line: line 4 lamps..., 5 ballast..., 6 vertical
/// angles, 7 horizontal angles, and candela row j (horizontal angle j) on line 8 + j.
fn ies_file(kind: u8, v: &[f64], h: &[f64], cd: impl Fn(f64, f64) -> f64) -> String {
    let mut s =
        format!("IESNA:LM-63-2002\n[TEST] synthetic\nTILT=NONE\n1 -1 1 {} {} {kind} 2 0 0 0\n", v.len(), h.len());
    s += &format!("1 1 0\n{}\n{}\n", join(v.iter().copied()), join(h.iter().copied()));
    for &hh in h {
        s += &join(v.iter().map(|&vv| cd(vv, hh)));
        s.push('\n');
    }
    s
}

fn parse(text: &str) -> IesProfile {
    IesProfile::parse(text, "synthetic.ies").unwrap_or_else(|e| panic!("{e}"))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn real_files_parse_and_their_flux_matches_an_independent_integration() {
    for path in real_files() {
        let p = IesProfile::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let exact = p.integrated_flux_lm();
        let numeric = numeric_flux(&p, 2000);
        let err = rel(exact, numeric);
        eprintln!(
            "{}: type {}, {}, {}x{} angles; closed form {exact:.3} lm, 2000x4000 midpoint {numeric:.3} lm, rel. error {err:.2e}",
            path.display(),
            p.photometric_type(),
            p.symmetry(),
            p.vertical_angles_deg().len(),
            p.horizontal_angles_deg().len()
        );
        assert!(err < 0.01, "{}: {exact} vs {numeric}", path.display());
        match p.stated_lumens() {
            // Relative photometry states the bare lamps' lumens: the luminaire can only lose light.
            Some(stated) => {
                let ratio = exact / stated;
                eprintln!("    stated {stated} lm (lamps); integrated/stated = {ratio:.4}");
                assert!(ratio > 0.0 && ratio <= 1.01, "{}: luminaire emits {ratio} x its lamps", path.display());
            }
            None => eprintln!("    absolute photometry (-1): no stated lumens"),
        }
    }
}

#[test]
fn real_files_equal_area_image_holds_the_flux() {
    for path in real_files() {
        let p = IesProfile::from_file(&path).unwrap();
        let res = 512;
        let image = p.to_equal_area_image(res);
        assert_eq!(image.len(), res * res);
        let flux: f64 = image.iter().map(|&x| f64::from(x)).sum::<f64>() * 4.0 * PI / (res * res) as f64;
        let err = rel(flux, p.integrated_flux_lm());
        eprintln!("{}: equal-area image {res}^2 flux rel. error {err:.2e}", path.display());
        assert!(err < 0.01);
    }
}

#[test]
fn real_file_header_and_counts() {
    let dir = data_dir();
    let p = IesProfile::from_file(&dir.join("luxcore/ASA_15M_R2.ies")).unwrap();
    assert_eq!(p.version, IesVersion::Lm63_2002);
    assert_eq!(p.keyword("TEST"), Some("LTL16760"));
    assert_eq!(p.keyword("LAMP"), Some("ONE 150-WATT CLEAR ED23.5 CERAMIC METAL HALIDE PULSE START, HORIZONTAL\nPOS."));
    assert_eq!((p.vertical_angles_deg().len(), p.horizontal_angles_deg().len()), (37, 73));
    assert_eq!(p.symmetry(), Symmetry::BilateralC0C180);
    assert_eq!(p.stated_lumens(), Some(13000.0));
    assert_eq!(p.candela(0.0, 0.0), 1666.0);
    let q = IesProfile::from_file(&dir.join("radeonprorender/ies_light_2.ies")).unwrap();
    assert_eq!(q.version, IesVersion::Lm63_1991);
    assert_eq!(q.lumens_per_lamp, None);
    assert_eq!(q.symmetry(), Symmetry::Full);
}

#[test]
fn isotropic_100_cd_integrates_to_400_pi() {
    let p = parse(&ies_file(1, &steps(0.0, 180.0, 5.0), &[0.0], |_, _| 100.0));
    assert_eq!(p.symmetry(), Symmetry::Rotational);
    assert!(rel(p.integrated_flux_lm(), 400.0 * PI) < 1e-12);
    let mut rng = SplitMix64::new(1);
    for _ in 0..1000 {
        assert!((p.candela_dir(direction(&mut rng)) - 100.0).abs() < 1e-9);
    }
    assert!(rel(numeric_flux(&p, 200), 400.0 * PI) < 1e-4);
}

#[test]
fn cosine_distribution_integrates_to_pi_i0() {
    let i0 = 1000.0;
    let p = parse(&ies_file(1, &steps(0.0, 90.0, 1.0), &[0.0], |v, _| i0 * v.to_radians().cos().max(0.0)));
    let flux = p.integrated_flux_lm();
    eprintln!("cosine: {flux} lm vs pi I0 = {}", PI * i0);
    assert!(rel(flux, PI * i0) < 1e-3);
    // Vertical angles stop at 90: the upper hemisphere is dark.
    assert_eq!(p.candela_dir(Vec3::new(0.3, 0.1, 0.5)), 0.0);
    assert!((p.candela_dir(-Vec3::Z) - i0).abs() < 1e-9);
}

/// A type C distribution 100 + 60 g(C) sin(gamma): its flux is 400 pi for any g with zero mean.
fn check_c_symmetry(h: Vec<f64>, expected: Symmetry, g: fn(f64) -> f64) {
    let v = steps(0.0, 180.0, 5.0);
    let truth = |gamma: f64, c: f64| 100.0 + 60.0 * g(c.to_radians()) * gamma.to_radians().sin();
    let p = parse(&ies_file(1, &v, &h, truth));
    assert_eq!(p.symmetry(), expected);
    let flux = p.integrated_flux_lm();
    assert!(rel(flux, 400.0 * PI) < 1e-9, "{expected:?}: {flux}");
    let numeric = numeric_flux(&p, 400);
    assert!(rel(numeric, flux) < 2e-3, "{expected:?}: {numeric} vs {flux}");
    // The unfolded interpolant follows the full-sphere function everywhere.
    let mut rng = SplitMix64::new(7);
    for _ in 0..2000 {
        let d = direction(&mut rng).as_dvec3();
        let gamma = d.x.hypot(d.y).atan2(-d.z).to_degrees();
        let c = d.y.atan2(d.x).to_degrees();
        let got = p.candela_dir(d.as_vec3());
        assert!((got - truth(gamma, c)).abs() < 0.5, "{expected:?} at C {c}, gamma {gamma}: {got}");
    }
}

#[test]
fn type_c_quadrant_symmetry() {
    check_c_symmetry(steps(0.0, 90.0, 5.0), Symmetry::Quadrant, |c| (2.0 * c).cos());
}

#[test]
fn type_c_bilateral_c0_c180_symmetry() {
    check_c_symmetry(steps(0.0, 180.0, 5.0), Symmetry::BilateralC0C180, f64::cos);
}

#[test]
fn type_c_bilateral_c90_c270_symmetry() {
    check_c_symmetry(steps(90.0, 270.0, 5.0), Symmetry::BilateralC90C270, f64::sin);
}

#[test]
fn type_c_full_sphere_data() {
    check_c_symmetry(steps(0.0, 360.0, 5.0), Symmetry::Full, |c| 0.5 * c.cos() + 0.3 * c.sin() + 0.2 * (2.0 * c).sin());
}

#[test]
fn type_c_full_data_ending_before_360_wraps() {
    let v = steps(0.0, 180.0, 10.0);
    let p = parse(&ies_file(1, &v, &steps(0.0, 350.0, 10.0), |_, c| 100.0 + 50.0 * c.to_radians().cos()));
    assert_eq!(p.symmetry(), Symmetry::Full);
    assert!(!p.warnings.is_empty());
    assert!(rel(p.integrated_flux_lm(), 400.0 * PI) < 1e-9);
    // Halfway between 350 and 360 (= 0): the mean of the two columns.
    assert!((p.candela(45.0, 355.0) - 0.5 * (p.candela(45.0, 350.0) + p.candela(45.0, 0.0))).abs() < 1e-9);
}

#[test]
fn type_c_frame_c0_is_plus_x_and_c90_is_plus_y() {
    // A single bright measurement at gamma 40, C 90.
    let (v, h) = (steps(0.0, 180.0, 10.0), steps(0.0, 360.0, 10.0));
    let p = parse(&ies_file(1, &v, &h, |g, c| if g == 40.0 && c == 90.0 { 500.0 } else { 0.0 }));
    let s = 40f32.to_radians().sin_cos();
    assert!((p.candela_dir(Vec3::new(0.0, s.0, -s.1)) - 500.0).abs() < 1e-3);
    assert!(p.candela_dir(Vec3::new(s.0, 0.0, -s.1)) < 1e-9);
    assert!((p.direction(40.0, 90.0) - Vec3::new(0.0, s.0, -s.1)).length() < 1e-6);
}

/// A spike at one (H, V) of an A or B file lands at the documented local direction.
fn check_ab_frame(kind: u8, h_at: f64, v_at: f64, expected: Vec3) {
    let (v, h) = (steps(-90.0, 90.0, 10.0), steps(-90.0, 90.0, 10.0));
    let p = parse(&ies_file(kind, &v, &h, |vv, hh| if vv == v_at && hh == h_at { 800.0 } else { 0.0 }));
    assert!((p.candela_dir(expected) - 800.0).abs() < 1e-3, "type {kind} H {h_at} V {v_at}");
    assert!((p.direction(v_at, h_at) - expected).length() < 1e-6);
    assert!((p.candela(v_at, h_at) - 800.0).abs() < 1e-9);
}

#[test]
fn type_b_frame_polar_axis_plus_y() {
    let (s, c) = (0.5f32, 0.75f32.sqrt());
    check_ab_frame(2, 30.0, 0.0, Vec3::new(s, 0.0, -c));
    check_ab_frame(2, 0.0, 30.0, Vec3::new(0.0, s, -c));
    check_ab_frame(2, 0.0, 0.0, -Vec3::Z);
}

#[test]
fn type_a_frame_polar_axis_plus_x() {
    let (s, c) = (0.5f32, 0.75f32.sqrt());
    check_ab_frame(3, 30.0, 0.0, Vec3::new(0.0, -s, -c));
    check_ab_frame(3, 0.0, 30.0, Vec3::new(s, 0.0, -c));
}

/// 1000 cd times the cosine to local -Z, which in A/B angles is cos H cos V: flux pi * 1000.
fn check_ab_cosine(kind: u8, h: Vec<f64>, v: Vec<f64>, expected: Symmetry) {
    let cd = |vv: f64, hh: f64| 1000.0 * vv.to_radians().cos() * hh.to_radians().cos();
    let p = parse(&ies_file(kind, &v, &h, cd));
    assert_eq!(p.symmetry(), expected);
    assert_eq!(p.photometric_type(), if kind == 2 { PhotometricType::B } else { PhotometricType::A });
    let flux = p.integrated_flux_lm();
    let numeric = numeric_flux(&p, 400);
    eprintln!("type {kind} {expected:?}: {flux} lm, numeric {numeric}, pi I0 = {}", PI * 1000.0);
    assert!(rel(flux, PI * 1000.0) < 2e-3);
    assert!(rel(numeric, flux) < 2e-3);
    let mut rng = SplitMix64::new(3);
    for _ in 0..1000 {
        let d = direction(&mut rng);
        let truth = 1000.0 * f64::from(-d.z).max(0.0);
        assert!((p.candela_dir(d) - truth).abs() < 5.0, "{d}: {} vs {truth}", p.candela_dir(d));
    }
}

#[test]
fn type_b_cosine_every_symmetry() {
    let (full, half) = (steps(-90.0, 90.0, 5.0), steps(0.0, 90.0, 5.0));
    check_ab_cosine(2, full.clone(), full.clone(), Symmetry::Full);
    check_ab_cosine(2, half.clone(), full.clone(), Symmetry::Lateral);
    check_ab_cosine(2, full.clone(), half.clone(), Symmetry::Vertical);
    check_ab_cosine(2, half.clone(), half.clone(), Symmetry::LateralAndVertical);
}

#[test]
fn type_a_cosine() {
    let (full, half) = (steps(-90.0, 90.0, 5.0), steps(0.0, 90.0, 5.0));
    check_ab_cosine(3, full.clone(), full, Symmetry::Full);
    check_ab_cosine(3, half.clone(), half, Symmetry::LateralAndVertical);
}

#[test]
fn type_b_mirrors_about_the_right_planes() {
    // Lateral data (H 0..90) with a V asymmetry: H mirrors (x -> -x), V must not (y -> -y).
    let p = parse(&ies_file(2, &steps(-90.0, 90.0, 10.0), &steps(0.0, 90.0, 10.0), |v, h| 100.0 + v + 0.5 * h));
    let d = p.direction(20.0, 30.0);
    assert!((p.candela_dir(Vec3::new(-d.x, d.y, d.z)) - p.candela_dir(d)).abs() < 1e-9);
    assert!((p.candela_dir(d) - 135.0).abs() < 1e-3);
    assert!((p.candela_dir(Vec3::new(d.x, -d.y, d.z)) - 95.0).abs() < 1e-3);
    // The back hemisphere is not measured.
    assert_eq!(p.candela_dir(Vec3::new(0.1, 0.2, 0.9)), 0.0);
}

/// The summary names the planes of its beam and field angles in the file's own angles: a type A
/// or B file's horizontal angles are not C-planes, so its table says "V = 0 (H sweep)" and
/// "H = 0 (V sweep)", never C0-C180. A spot 10 degrees wide in H and 30 in V (Gaussian s) has
/// the beam angle 2 s sqrt(2 ln 2) of each in the plane so named: local XZ sweeps H for type B,
/// local YZ for type A (their frames, tested above).
#[test]
fn summaries_of_type_a_and_b_files_name_their_planes_by_type_not_as_c_planes() {
    use kelvin::scene::ies::IesSummary;
    let beam = |s: f64| 2.0 * s * (2.0 * 2f64.ln()).sqrt();
    let spot = |v: f64, h: f64| 1000.0 * (-h * h / (2.0 * 10.0 * 10.0) - v * v / (2.0 * 30.0 * 30.0)).exp();
    let (v, h) = (steps(-90.0, 90.0, 0.5), steps(-90.0, 90.0, 0.5));
    for kind in [2u8, 3] {
        let summary = IesSummary::of(&parse(&ies_file(kind, &v, &h, spot)));
        let table = summary.to_string();
        let (h_sweep, v_sweep) = match kind {
            2 => ((summary.beam_angle_deg, 0), (summary.beam_angle_c90_deg, 1)),
            _ => ((summary.beam_angle_c90_deg, 1), (summary.beam_angle_deg, 0)),
        };
        eprintln!("type {kind}: {}", table.lines().find(|l| l.starts_with("beam")).unwrap_or_default());
        assert_eq!(summary.angle_planes[h_sweep.1], "V = 0 (H sweep)", "type {kind}");
        assert_eq!(summary.angle_planes[v_sweep.1], "H = 0 (V sweep)", "type {kind}");
        assert!((h_sweep.0.unwrap() - beam(10.0)).abs() < 0.2, "type {kind}: H beam {:?}", h_sweep.0);
        assert!((v_sweep.0.unwrap() - beam(30.0)).abs() < 0.2, "type {kind}: V beam {:?}", v_sweep.0);
        assert!(!table.contains("C0-C180") && !table.contains("C90-C270"), "type {kind}:\n{table}");
        assert!(table.contains("(XZ / V = 0 (H sweep))") || table.contains("(YZ / V = 0 (H sweep))"), "{table}");
    }
    let c = IesSummary::of(&parse(&ies_file(1, &steps(0.0, 180.0, 5.0), &[0.0], |g, _| 100.0 + g)));
    assert_eq!(c.angle_planes, ["C0-C180", "C90-C270"]);
    assert!(c.to_string().contains("(XZ / C0-C180)"));
}

#[test]
fn beam_and_field_angles_of_a_gaussian_spot() {
    // I = 1000 exp(-gamma^2 / (2 s^2)): 50% at gamma = s sqrt(2 ln 2), 10% at s sqrt(2 ln 10).
    let s: f64 = 10.0;
    let p = parse(&ies_file(1, &steps(0.0, 180.0, 0.5), &[0.0], |g, _| 1000.0 * (-g * g / (2.0 * s * s)).exp()));
    let beam = 2.0 * s * (2.0 * 2f64.ln()).sqrt();
    let field = 2.0 * s * (2.0 * 10f64.ln()).sqrt();
    let (b, f) = (p.beam_angle_deg().unwrap(), p.field_angle_deg().unwrap());
    eprintln!("gaussian spot: beam {b} (expected {beam}), field {f} (expected {field})");
    assert!((b - beam).abs() < 0.1 && (f - field).abs() < 0.1);
    assert!((p.max_candela() - 1000.0).abs() < 1e-9);
    let iso = parse(&ies_file(1, &[0.0, 180.0], &[0.0], |_, _| 5.0));
    assert_eq!(iso.beam_angle_deg(), None);
}

#[test]
fn old_and_new_versions_keywords_and_separators() {
    // 1986: no version line, free label lines; numbers split across lines and commas.
    let t86 = "Acme downlight\nsome test lab\nTILT=NONE\n1,1000,1,3\n1,1,2,0,0,0\n1,1,0\n0,45,90\n0\n100,50\n,0\n";
    let p = parse(t86);
    assert_eq!(p.version, IesVersion::Lm63_1986);
    assert_eq!(p.keywords, vec![(String::new(), "Acme downlight".into()), (String::new(), "some test lab".into())]);
    assert_eq!(p.candela(45.0, 0.0), 50.0);
    for (tag, version) in [
        ("IESNA91", IesVersion::Lm63_1991),
        ("IESNA:LM-63-1995", IesVersion::Lm63_1995),
        ("IESNA:LM-63-2002", IesVersion::Lm63_2002),
        ("IES:LM-63-2019", IesVersion::Lm63_2019),
    ] {
        let text = format!(
            "{tag}\r\n[TEST] t1\r\n[LUMINAIRE] long\r\n[MORE] name\r\n[_X] y\r\nTILT=NONE\r\n1 500 1 2 1 1 1 0 0 0\r\n1 1 10\r\n0 90\r\n0\r\n10 10\r\n"
        );
        let p = parse(&text);
        assert_eq!(p.version, version);
        assert_eq!(p.keywords.len(), 3);
        assert_eq!(p.keyword("luminaire"), Some("long\nname"));
        assert_eq!(p.keyword("_X"), Some("y"));
    }
}

#[test]
fn ballast_factors_by_version() {
    let body = "TILT=NONE\n1 1000 2 2 1 1 2 0 0 0\n0.5 0.8 10\n0 180\n0\n10 10\n";
    assert!((parse(&format!("IESNA91\n{body}")).candela(0.0, 0.0) - 8.0).abs() < 1e-12); // 2 x 0.5 x 0.8
    assert!((parse(&format!("IESNA:LM-63-2002\n{body}")).candela(0.0, 0.0) - 10.0).abs() < 1e-12); // 2 x 0.5
}

#[test]
fn tilt_include_and_tilt_file() {
    let text = "IESNA:LM-63-1995\nTILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.8\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 180\n0\n1 1\n";
    let p = parse(text);
    assert_eq!(p.tilt, Tilt::Include { geometry: 1, angles_deg: vec![0.0, 45.0, 90.0], factors: vec![1.0, 0.9, 0.8] });
    let p = parse(&text.replace("TILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.8\n", "TILT=lamp.tlt\n"));
    assert_eq!(p.tilt, Tilt::File("lamp.tlt".into()));
    assert!(p.warnings.iter().any(|w| w.contains("lamp.tlt")));
}

/// The base of the broken-input tests: 3 vertical x 2 horizontal angles, candela rows on lines 8, 9.
fn small_file() -> String {
    ies_file(1, &[0.0, 45.0, 90.0], &[0.0, 180.0], |v, _| 100.0 - v)
}

fn expect_error(text: &str, line: usize, check: impl Fn(&IesError) -> bool) {
    let e = IesProfile::parse(text, "broken.ies").expect_err("should fail");
    eprintln!("{e}");
    assert_eq!(e.line(), Some(line), "{e}");
    assert!(check(&e), "unexpected variant: {e:?}");
    let msg = e.to_string();
    assert!(msg.contains("broken.ies") && msg.contains(&format!("line {line}")), "{msg}");
}

#[test]
fn broken_inputs_name_the_line() {
    let good = small_file();
    parse(&good);
    let lines: Vec<&str> = good.lines().collect();
    let with_line = |n: usize, new: &str| {
        let mut l = lines.clone();
        l[n - 1] = new;
        l.join("\n")
    };
    // Truncated: the last candela row is missing; the file ends at line 8.
    expect_error(&lines[..8].join("\n"), 8, |e| matches!(e, IesError::Truncated { .. }));
    // No TILT line at all.
    expect_error("IESNA:LM-63-2002\n[TEST] x\n", 2, |e| matches!(e, IesError::Truncated { .. }));
    expect_error("", 1, |e| matches!(e, IesError::Truncated { .. }));
    // Wrong counts: one horizontal angle too many, or too few.
    // Too many horizontal angles: the angle list runs into the first candela row.
    expect_error(&with_line(4, "1 -1 1 3 3 1 2 0 0 0"), 8, |e| matches!(e, IesError::NonMonotonic { .. }));
    // Too few: values are left over.
    expect_error(&with_line(4, "1 -1 1 3 1 1 2 0 0 0"), 8, |e| matches!(e, IesError::TrailingData { .. }));
    expect_error(&with_line(4, "1 -1 1 2 2 1 2 0 0 0"), 7, |e| matches!(e, IesError::NonMonotonic { .. }));
    expect_error(&format!("{good}5 6\n"), 10, |e| matches!(e, IesError::TrailingData { .. }));
    // Values.
    expect_error(
        &with_line(9, "100 -5 10"),
        9,
        |e| matches!(e, IesError::NegativeCandela { value, .. } if *value == -5.0),
    );
    expect_error(&with_line(8, "100 5x5 10"), 8, |e| matches!(e, IesError::NotANumber { found, .. } if found == "5x5"));
    expect_error(&with_line(8, "100 NaN 10"), 8, |e| matches!(e, IesError::NotFinite { .. }));
    expect_error(&with_line(6, "0 45 inf"), 6, |e| matches!(e, IesError::NotFinite { .. }));
    expect_error(&with_line(6, "0 90 45"), 6, |e| matches!(e, IesError::NonMonotonic { .. }));
    expect_error(&with_line(4, "1 -1 1 3 2 4 2 0 0 0"), 4, |e| matches!(e, IesError::UnknownPhotometricType { .. }));
    expect_error(&with_line(4, "1 -1 1 1000000000 2 1 2 0 0 0"), 4, |e| matches!(e, IesError::BadCount { .. }));
    expect_error(&with_line(4, "1 -1 1 3 1e9 1 2 0 0 0"), 4, |e| matches!(e, IesError::BadCount { .. }));
    expect_error(&with_line(4, "1 -1 1 3 2.5 1 2 0 0 0"), 4, |e| matches!(e, IesError::BadCount { .. }));
    expect_error(&with_line(4, "1 -1 -2 3 2 1 2 0 0 0"), 4, |e| matches!(e, IesError::BadValue { .. }));
    expect_error(&with_line(4, "1 -1 1 3 2 1 7 0 0 0"), 4, |e| matches!(e, IesError::BadValue { .. }));
    expect_error(&with_line(7, "0 120"), 7, |e| matches!(e, IesError::UnsupportedAngles { .. }));
    expect_error(&with_line(3, "TILT="), 3, |e| matches!(e, IesError::BadValue { .. }));
}

#[test]
fn mutated_files_never_panic() {
    let mut bases =
        vec![small_file(), ies_file(2, &steps(0.0, 90.0, 30.0), &steps(-90.0, 90.0, 45.0), |v, h| v + h + 100.0)];
    bases.push(bases[0].replace("TILT=NONE", "TILT=INCLUDE\n1 2 0 90 1 0.5"));
    let mut rng = SplitMix64::new(42);
    let pieces = ["-1", "0", "1e9", "nan", ",", "\n", "[MORE] x", "TILT=NONE", "999999", "-0", "360", "3", "\u{1a}"];
    let (mut ok, mut err) = (0, 0);
    for round in 0..3000 {
        let base = &bases[round % bases.len()];
        let mut tokens: Vec<String> = base.split(' ').map(str::to_string).collect();
        for _ in 0..1 + index_below(&mut rng, 4) {
            if tokens.is_empty() {
                tokens.push("1".into());
            }
            let i = index_below(&mut rng, tokens.len());
            match index_below(&mut rng, 4) {
                0 => drop(tokens.remove(i)),
                1 => tokens.insert(i, pieces[index_below(&mut rng, pieces.len())].to_string()),
                2 => tokens[i] = pieces[index_below(&mut rng, pieces.len())].to_string(),
                _ => tokens.truncate(i.max(1)),
            }
        }
        match IesProfile::parse(&tokens.join(" "), "mutant") {
            Ok(p) => {
                ok += 1;
                let _ = (p.integrated_flux_lm(), p.beam_angle_deg(), p.candela_dir(Vec3::new(0.3, -0.2, -1.0)));
                let _ = p.to_equal_area_image(8);
            }
            Err(e) => {
                err += 1;
                assert!(e.line().is_some(), "{e}");
            }
        }
    }
    eprintln!("mutants: {ok} parsed, {err} rejected");
}

fn run_cli(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("run kelvin")
}

#[test]
fn cli_prints_json_plots_and_reports_bad_files() {
    let tmp = std::env::temp_dir().join(format!("kelvin-ies-test-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let file = real_files().into_iter().next().expect("a real IES file");
    let svg = tmp.join("polar.svg");
    let out = run_cli(&["ies", file.to_str().unwrap(), "--json", "--plot", svg.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    for key in [
        "version",
        "keywords",
        "photometric_type",
        "symmetry",
        "lamps",
        "lumens_per_lamp",
        "stated_lumens",
        "integrated_lumens",
        "max_candela",
        "beam_angle_deg",
        "field_angle_deg",
    ] {
        assert!(json.get(key).is_some(), "missing key {key} in {json}");
    }
    assert!(json["integrated_lumens"].as_f64().unwrap() > 0.0);
    assert!(std::fs::metadata(&svg).unwrap().len() > 1000);

    let bad = tmp.join("bad.ies");
    std::fs::write(&bad, small_file().replace("100 55 10", "100 -55 10")).unwrap();
    let out = run_cli(&["ies", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.ies") && stderr.contains("line 8"), "{stderr}");
    let _ = std::fs::remove_dir_all(&tmp);
}
