//! Tracing the batched shadow rays as any-hit queries against the scene BVH.

use bevy_ecs::prelude::*;

use crate::geometry::{SceneBvh, SurfacePoint};
use crate::shading::{RunReport, Settings};

use super::{ShadowRays, Work};

/// Shadow rays are traced only when asked for, when there are rays and when some geometry can
/// occlude them.
pub fn plan_shadows(
    settings: Res<Settings>,
    rays: Res<ShadowRays>,
    bvh: Res<SceneBvh>,
    mut work: ResMut<Work>,
    mut report: ResMut<RunReport>,
) {
    let (run, why) = if !settings.shadows {
        (false, "shadows are off in Settings".to_string())
    } else if rays.is_empty() {
        (false, "no shadow rays (no samples, or every light has casts_shadows = false)".to_string())
    } else if bvh.primitive_count() == 0 {
        (false, "no occluding geometry".to_string())
    } else {
        (true, format!("{} rays against {} primitives", rays.len(), bvh.primitive_count()))
    };
    work.shadows = run;
    report.record("trace_shadow_rays", run, why);
}

/// Builds offset segments (off the shading surface and off the light's surface, by
/// `Settings::shadow_offset`) and traces them, in one parallel pass; fills `ShadowRays::occluded`.
pub fn trace_shadow_rays(mut rays: ResMut<ShadowRays>, bvh: Res<SceneBvh>, settings: Res<Settings>) {
    use rayon::prelude::*;
    let r = &mut *rays;
    let offset = settings.shadow_offset;
    let mut occluded = std::mem::take(&mut r.occluded);
    (0..r.origin.len())
        .into_par_iter()
        .with_min_len(crate::geometry::RAY_CHUNK)
        .map(|i| {
            let from = SurfacePoint { p: r.origin[i], p_error: r.origin_error[i], n: r.origin_normal[i] };
            let segment = if r.to_infinity[i] {
                offset.spawn_ray(&from, (r.target[i] - r.origin[i]).normalize())
            } else if r.target_normal[i] == glam::Vec3::ZERO {
                offset.spawn_ray_to_point(&from, r.target[i])
            } else {
                offset.spawn_ray_to(&from, &SurfacePoint::from_point(r.target[i], r.target_normal[i]))
            };
            bvh.occluded(&segment)
        })
        .collect_into_vec(&mut occluded);
    r.occluded = occluded;
}
