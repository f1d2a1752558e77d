//! Tracing the batched shadow rays as any-hit queries against the scene BVH.

use bevy_ecs::prelude::*;

use crate::geometry::{SceneBvh, SurfacePoint};
use crate::shading::{RunReport, Settings, ShadingBatch};

use super::{ShadowRays, ShadowTarget, Work};

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

/// Builds offset segments from each entry's batch point (off the shading surface, and off the
/// light's surface, by `Settings::shadow_offset`) and traces them, in one parallel pass; fills
/// `ShadowRays::occluded`.
pub fn trace_shadow_rays(
    mut rays: ResMut<ShadowRays>,
    batch: Res<ShadingBatch>,
    bvh: Res<SceneBvh>,
    settings: Res<Settings>,
) {
    use rayon::prelude::*;
    let offset = settings.shadow_offset;
    let r = &mut *rays;
    let k = r.entries_per_point.max(1);
    let (kind, target, target_normal) = (&r.kind, &r.target, &r.target_normal);
    r.occluded.par_iter_mut().enumerate().with_min_len(crate::geometry::RAY_CHUNK).for_each(|(e, occluded)| {
        let i = e / k;
        let from = SurfacePoint { p: batch.position[i], p_error: batch.position_error[i], n: batch.normal[i] };
        let segment = match kind[e] {
            ShadowTarget::None => return,
            ShadowTarget::Infinity => offset.spawn_ray(&from, (target[e] - from.p).normalize()),
            ShadowTarget::Point => offset.spawn_ray_to_point(&from, target[e]),
            ShadowTarget::Surface => offset.spawn_ray_to(&from, &SurfacePoint::from_point(target[e], target_normal[e])),
        };
        *occluded = bvh.occluded(&segment);
    });
}
