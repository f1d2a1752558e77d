//! Tracing the batched shadow rays as any-hit queries against the scene BVH.

use bevy_ecs::prelude::*;

use glam::Vec3;

use crate::geometry::ray::spawn_rays_to_points_lanes;
use crate::geometry::{GeometryId, RAY_CHUNK, Ray, SHADOW_EPSILON, SceneBvh, ShadowOffset, SurfacePoint};
use crate::lanes::{F32x16, LANES, Vec3x16};
use crate::shading::{RunReport, SceneBounds, Settings, ShadingBatch};

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
        (
            false,
            "no shadow rays (no samples, every light has casts_shadows = false, or nothing can block them)".to_string(),
        )
    } else if bvh.primitive_count() == 0 {
        (false, "no occluding geometry".to_string())
    } else {
        (true, format!("{} rays against {} primitives", rays.len(), bvh.primitive_count()))
    };
    work.shadows = run;
    if run {
        report.record_count("trace_shadow_rays", true, why, rays.len() as u64, "rays");
    } else {
        report.record("trace_shadow_rays", run, why);
    }
}

/// Builds offset segments from each entry's batch point (off the shading surface, and off the
/// light's surface, by `Settings::shadow_offset`) and traces them, in one parallel pass; fills
/// `ShadowRays::occluded`.
pub fn trace_shadow_rays(
    mut rays: ResMut<ShadowRays>,
    batch: Res<ShadingBatch>,
    bvh: Res<SceneBvh>,
    settings: Res<Settings>,
    bounds: Res<SceneBounds>,
) {
    use rayon::prelude::*;
    let offset = settings.shadow_offset;
    let r = &mut *rays;
    let k = r.entries_per_point.max(1);
    let (kind, target, target_normal) = (&r.kind, &r.target, &r.target_normal);
    // One entry per point is the common case; it spares a 64-bit division per entry.
    let point_of = |e: usize| if k == 1 { e } else { e / k };
    let from = |i: usize| SurfacePoint { p: batch.position[i], p_error: batch.position_error[i], n: batch.normal[i] };
    let segment = |e: usize| {
        let from = from(point_of(e));
        match kind[e] {
            ShadowTarget::None => NO_RAY,
            ShadowTarget::Infinity => offset.spawn_ray(&from, (target[e] - from.p).normalize()),
            ShadowTarget::Point => offset.spawn_ray_to_point(&from, target[e]),
            ShadowTarget::Surface => offset.spawn_ray_to(&from, &SurfacePoint::from_point(target[e], target_normal[e])),
        }
    };
    // Segments traced LANES at a time (a pixel's samples: coherent packets). Blocks of
    // point-light segments, one entry per point, are built from columns by a lane kernel; others
    // one segment at a time. Blocks whose points lie apart (a path's later bounces) are traced
    // one ray at a time: a packet's shared traversal would visit every point's nodes.
    let scattered = SCATTERED_FRACTION * bounds.sphere.radius;
    let chunks = r.occluded.par_chunks_mut(RAY_CHUNK).enumerate();
    r.blocked = chunks
        .map(|(c, chunk)| {
            crate::lanes::widest(
                #[inline(always)]
                || {
                    let mut b = 0;
                    while b < chunk.len() {
                        let n = LANES.min(chunk.len() - b);
                        let first = c * RAY_CHUNK + b;
                        let mut origins = [GeometryId::NONE; LANES];
                        match batch.geometry.get(first..first + LANES) {
                            Some(g) if k == 1 => origins.copy_from_slice(g),
                            _ => {
                                for (l, o) in origins.iter_mut().enumerate().take(n) {
                                    *o = batch.geometry_of(point_of(first + l));
                                }
                            }
                        }
                        if spread(&batch.position, (first..first + n).map(point_of)) > scattered {
                            for (l, occluded) in chunk[b..b + n].iter_mut().enumerate() {
                                *occluded = bvh.occluded_from(&segment(first + l), origins[l]);
                            }
                            b += LANES;
                            continue;
                        }
                        // Cache-line aligned: the packet loads these columns whole.
                        #[repr(C, align(64))]
                        struct Aligned<T>(T);
                        let points = k == 1 && n == LANES && offset == ShadowOffset::ErrorBound;
                        let segments = if points && kind[first..first + LANES].iter().all(|&t| t == ShadowTarget::Point)
                        {
                            let columns = |v: &[Vec3]| Vec3x16::load(v, first);
                            // Origin, its error bound, normal and target. (Not `array::map`: its closure
                            // may stay out of the wide code.)
                            let ends = Aligned([
                                columns(&batch.position),
                                columns(&batch.position_error),
                                columns(&batch.normal),
                                columns(target),
                            ]);
                            let [origin, error, normal, to] = &ends.0;
                            let [o, d] = spawn_rays_to_points_lanes([origin, error, normal], to);
                            Aligned((o, d, F32x16::splat(1.0 - SHADOW_EPSILON)))
                        } else {
                            let mut s = Aligned((Vec3x16::ZERO, Vec3x16::ZERO, F32x16::ZERO));
                            let (o, d, t) = &mut s.0;
                            for l in 0..n {
                                let ray = segment(first + l);
                                o.set_lane(l, ray.origin);
                                d.set_lane(l, ray.dir);
                                t[l] = ray.t_max;
                            }
                            s
                        };
                        let (o, d, t) = &segments.0;
                        let blocked = bvh.occluded_packet(o, d, t, n, &origins);
                        for (l, occluded) in chunk[b..b + n].iter_mut().enumerate() {
                            *occluded = (blocked >> l) & 1 != 0;
                        }
                        b += LANES;
                    }
                    chunk.iter().filter(|&&o| o).count()
                },
            )
        })
        .sum();
}

/// Points of a block further apart than this fraction of the scene's bounding radius are traced
/// one ray at a time. A pixel's samples on the surface the camera sees lie well within it at
/// any useful resolution; the surfaces its paths bounce to are spread over the scene.
const SCATTERED_FRACTION: f32 = 0.1;

/// The largest extent, over the axes, of the box around `points` (non-finite ones ignored).
#[inline(always)]
fn spread(positions: &[Vec3], points: impl Iterator<Item = usize>) -> f32 {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for i in points {
        let p = positions[i];
        if p.is_finite() {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    (hi - lo).max_element().max(0.0)
}

/// The ray of an entry without one: invalid (zero direction), so never occluded.
const NO_RAY: Ray = Ray::new(Vec3::ZERO, Vec3::ZERO);
