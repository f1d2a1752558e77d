//! Area lights (d): irradiance estimated by `sample_li` (mean of L cos / pdf) against closed forms:
//! a disk on its axis, spheres (pi L (r/d)^2 cos theta, also at 1e-3 r and 1.2e-7 r from the
//! surface, on it and inside it), and rectangles and triangles by Lambert's polygon formula, on
//! both sides of the spherical-sampling band. Relative errors are printed with `--nocapture`.

mod common;

use std::f64::consts::PI;

use glam::{Quat, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::area::SamplingStrategy;
use kelvin::light::{AreaShape, LightSampleContext};
use kelvin::rng::SplitMix64;

use common::area::*;
use common::assert_mc;

#[test]
fn irradiance_of_disk_on_axis() {
    let mut rng = SplitMix64::new(6);
    for l in [light(), two_sided()] {
        let d = disk(&l);
        let AreaShape::Disk { center, normal, radius } = d.shape else { unreachable!() };
        for h in [0.05f32, 0.7, 4.0] {
            let ctx = LightSampleContext::on_surface(center + normal * h, -normal);
            let sin2 = (radius * radius / (radius * radius + h * h)) as f64;
            let name = format!("(d) irradiance disk on axis h = {h} two_sided = {}", l.two_sided);
            assert_mc(&name, &irradiance(&d, &ctx, 500_000, &mut rng), PI * nits(&d) * sin2);
        }
        // Behind a one-sided disk: nothing.
        let ctx = LightSampleContext::on_surface(center - normal * 0.5, normal);
        let e = irradiance(&d, &ctx, 10_000, &mut rng).mean();
        if l.two_sided { assert!(e > 0.0) } else { assert_eq!(e, 0.0) }
    }
}

#[test]
fn irradiance_of_sphere_from_outside() {
    let mut rng = SplitMix64::new(7);
    let s = sphere(&light());
    let AreaShape::Sphere { center, .. } = s.shape else { unreachable!() };
    for (k, (offset, tilt)) in
        [(Vec3::new(2.0, 0.5, -1.0), 0.3f32), (Vec3::new(0.0, -0.9, 0.2), 0.1), (Vec3::new(-5.0, 3.0, 1.0), 1.2)]
            .into_iter()
            .enumerate()
    {
        let p = center + offset;
        let n = Quat::from_axis_angle(offset.normalize().any_orthonormal_vector(), tilt) * (-offset.normalize());
        let ctx = LightSampleContext::on_surface(p, n);
        let name = format!("(d) irradiance sphere point {k} ({:?})", s.strategy(p));
        assert_mc(&name, &irradiance(&s, &ctx, 500_000, &mut rng), sphere_irradiance(&s, &ctx));
    }
}

#[test]
fn irradiance_of_tiny_sphere_below_taylor_threshold() {
    let (s, ctx) = tiny_sphere(&light());
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Cone);
    assert_mc(
        "(d) irradiance tiny sphere sin^2 = 1e-8",
        &irradiance(&s, &ctx, 200_000, &mut SplitMix64::new(8)),
        sphere_irradiance(&s, &ctx),
    );
    // Near pbrt's Taylor threshold sin^2 = 6.85e-4.
    let s = light().resolve_sphere(0.0262, &Transform::IDENTITY).unwrap();
    let ctx = LightSampleContext::on_surface(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y);
    assert_mc(
        "(d) irradiance sphere sin^2 = 6.86e-4",
        &irradiance(&s, &ctx, 200_000, &mut SplitMix64::new(9)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_of_sphere_at_1e_3_r_outside() {
    let (s, ctx) = sphere_at_origin(&light(), 1.0 + 1e-3);
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Cone);
    assert_mc(
        "(d) irradiance sphere d = r (1 + 1e-3)",
        &irradiance(&s, &ctx, 1_000_000, &mut SplitMix64::new(10)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_of_sphere_at_1e_7_r_outside() {
    let (s, ctx) = sphere_at_origin(&light(), 1.0 + 1e-7);
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Area);
    assert_mc(
        "(d) irradiance sphere d = r (1 + 1.2e-7)",
        &irradiance(&s, &ctx, 1_000_000, &mut SplitMix64::new(11)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_at_shading_point_on_sphere_surface() {
    let mut rng = SplitMix64::new(12);
    for l in [light(), two_sided()] {
        let (s, _) = sphere_at_origin(&l, 1.0);
        let p = Vec3::new(0.0, 0.0, 1.0); // exactly on the surface
        let inward = LightSampleContext::on_surface(p, -p.normalize());
        let outward = LightSampleContext::on_surface(p, p.normalize());
        // Facing in, a two-sided sphere fills the hemisphere (E = pi L); a one-sided one shows
        // only its unlit inside. Facing out, the sphere is below the horizon.
        let want_in = if l.two_sided { PI * nits(&s) } else { 0.0 };
        assert_mc(
            &format!("(d) irradiance on sphere surface, facing in, two_sided = {}", l.two_sided),
            &irradiance(&s, &inward, 500_000, &mut rng),
            want_in,
        );
        let e_out = irradiance(&s, &outward, 100_000, &mut rng).mean();
        assert!(e_out.abs() <= 1e-3 * nits(&s), "facing out: {e_out}");
    }
}

#[test]
fn irradiance_inside_sphere() {
    let mut rng = SplitMix64::new(13);
    for l in [light(), two_sided()] {
        let (s, _) = sphere_at_origin(&l, 1.0);
        let ctx = LightSampleContext::on_surface(Vec3::new(0.3, -0.4, 0.2), Vec3::new(1.0, 2.0, -0.5).normalize());
        assert_eq!(s.strategy(ctx.p), SamplingStrategy::Area);
        let want = if l.two_sided { PI * nits(&s) } else { 0.0 };
        assert_mc(
            &format!("(d) irradiance inside sphere, two_sided = {}", l.two_sided),
            &irradiance(&s, &ctx, 500_000, &mut rng),
            want,
        );
    }
}

#[test]
fn irradiance_of_rectangle_in_both_strategy_bands() {
    let mut rng = SplitMix64::new(14);
    let l = light();
    let (r, ctx) = far_tiny_rectangle(&l);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle far tiny 1e-4 sr (Area)", &irradiance(&r, &ctx, 200_000, &mut rng), want);

    let (r, ctx) = unit_rectangle_above(&l, 1.0);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::SphericalRectangle);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle moderate (Spherical)", &irradiance(&r, &ctx, 500_000, &mut rng), want);

    let (r, ctx) = unit_rectangle_above(&l, 0.01);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle near huge 6.23 sr (Area)", &irradiance(&r, &ctx, 2_000_000, &mut rng), want);

    // A tilted rectangle and a tilted receiver, two-sided, seen from behind.
    let r = rectangle(&two_sided());
    let n = r.shape.plane_normal().unwrap();
    let AreaShape::Rectangle { corner, ex, ey } = r.shape else { unreachable!() };
    let p = corner + 0.3 * ex + 0.6 * ey - 0.8 * n;
    let ctx = LightSampleContext::on_surface(p, Quat::from_axis_angle(ex.normalize(), 0.2) * n);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc(
        &format!("(d) irradiance tilted rectangle from behind two-sided ({:?})", r.strategy(p)),
        &irradiance(&r, &ctx, 500_000, &mut rng),
        want,
    );
}

#[test]
fn irradiance_of_triangles_1e_8_sr_moderate_and_nearly_2_pi_sr() {
    let mut rng = SplitMix64::new(15);
    let l = light();
    let (t, ctx) = tiny_triangle(&l);
    let omega = kelvin::sampling::triangle_solid_angle(corners(&t.shape).try_into().unwrap(), ctx.p);
    assert!((omega - 1e-8).abs() < 1e-11, "{omega}");
    assert_eq!(t.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle 1e-8 sr (Area)", &irradiance(&t, &ctx, 100_000, &mut rng), want);

    let t = moderate_triangle(&l);
    let n = t.shape.plane_normal().unwrap();
    let p = corners(&t.shape).iter().sum::<Vec3>() / 3.0 + 0.7 * n;
    let ctx = LightSampleContext::on_surface(p, Quat::from_axis_angle(n.any_orthonormal_vector(), 0.15) * -n);
    assert_eq!(t.strategy(p), SamplingStrategy::SphericalTriangle);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle moderate (Spherical)", &irradiance(&t, &ctx, 1_000_000, &mut rng), want);

    let (t, ctx) = near_hemisphere_triangle(&l);
    let omega = kelvin::sampling::triangle_solid_angle(corners(&t.shape).try_into().unwrap(), ctx.p);
    assert!(omega > 6.22 && omega < 2.0 * std::f32::consts::PI, "{omega}");
    assert_eq!(t.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle nearly 2 pi sr (Area)", &irradiance(&t, &ctx, 2_000_000, &mut rng), want);
}
