//! Tracing a block's shadow segments as any-hit queries against the scene BVH, inside the sampling
//! pass (see `sample_direct_lighting`), while the chunk's entries are still in cache.

use glam::Vec3;

use crate::geometry::ray::spawn_rays_to_points_lanes;
use crate::geometry::{GeometryId, Ray, SHADOW_EPSILON, SceneBvh, ShadowOffset, SurfacePoint};
use crate::lanes::{F32x16, LANES, Vec3x16};
use crate::shading::{SceneBounds, Settings, ShadingBatch};

use super::ShadowTarget;

/// What tracing a block of segments reads.
pub(super) struct Shadows<'a> {
    batch: &'a ShadingBatch,
    bvh: &'a SceneBvh,
    offset: ShadowOffset,
    /// Entries per batch point.
    k: usize,
    /// Blocks whose points lie further apart than this are traced one ray at a time.
    scattered: f32,
}

impl<'a> Shadows<'a> {
    /// The tracer of a batch with `k` entries per point; None when nothing is traced: shadows are
    /// off, or no geometry can block a ray.
    pub(super) fn new(
        batch: &'a ShadingBatch,
        bvh: &'a SceneBvh,
        settings: &Settings,
        bounds: &SceneBounds,
        k: usize,
    ) -> Option<Self> {
        (settings.shadows && bvh.primitive_count() > 0).then(|| Shadows {
            batch,
            bvh,
            offset: settings.shadow_offset,
            k: k.max(1),
            scattered: SCATTERED_FRACTION * bounds.sphere.radius,
        })
    }

    /// The batch point of global entry `e`.
    #[inline(always)]
    fn point_of(&self, e: usize) -> usize {
        // One entry per point is the common case; it spares a 64-bit division per entry.
        if self.k == 1 { e } else { e / self.k }
    }

    /// The offset segment of global entry `e`, which ends at `target` (normal `target_normal` for
    /// a surface), from its batch point off the shading surface and off the light's surface.
    #[inline(always)]
    fn segment(&self, e: usize, kind: ShadowTarget, target: Vec3, target_normal: Vec3) -> Ray {
        let i = self.point_of(e);
        let b = self.batch;
        let from = SurfacePoint { p: b.position[i], p_error: b.position_error[i], n: b.normal[i] };
        match kind {
            ShadowTarget::None => NO_RAY,
            ShadowTarget::Infinity => self.offset.spawn_ray(&from, (target - from.p).normalize()),
            ShadowTarget::Point => self.offset.spawn_ray_to_point(&from, target),
            ShadowTarget::Surface => self.offset.spawn_ray_to(&from, &SurfacePoint::from_point(target, target_normal)),
        }
    }

    /// Traces the segments of global entries `first..first + n` (`n = kind.len() <= LANES`; their
    /// ends in the block-local `kind`, `target` and `target_normal`) and returns the blocked ones
    /// as a mask. A block is a pixel's samples, traced as one coherent packet, unless its points
    /// lie apart (a path's later bounces): then one ray at a time, as a packet's shared traversal
    /// would visit every point's nodes. Point-light segments of one entry per point are built by
    /// a lane kernel from the batch's columns.
    #[inline(always)]
    pub(super) fn trace_block(
        &self,
        first: usize,
        kind: &[ShadowTarget],
        target: &[Vec3],
        target_normal: &[Vec3],
    ) -> u32 {
        let (n, batch) = (kind.len(), self.batch);
        let mut origins = [GeometryId::NONE; LANES];
        match batch.geometry.get(first..first + LANES) {
            Some(g) if self.k == 1 && n == LANES => origins.copy_from_slice(g),
            _ => {
                for (l, o) in origins.iter_mut().enumerate().take(n) {
                    *o = batch.geometry_of(self.point_of(first + l));
                }
            }
        }
        if spread(&batch.position, (first..first + n).map(|e| self.point_of(e))) > self.scattered {
            let mut blocked = 0;
            for l in 0..n {
                let ray = self.segment(first + l, kind[l], target[l], target_normal[l]);
                // Inside the sampling pass's `lanes::widest`: no dispatch per ray.
                blocked |= (self.bvh.occluded_in_lanes(&ray, origins[l]) as u32) << l;
            }
            return blocked;
        }
        // Cache-line aligned: the packet loads these columns whole.
        #[repr(C, align(64))]
        struct Aligned<T>(T);
        let points = self.k == 1 && n == LANES && self.offset == ShadowOffset::ErrorBound;
        let segments = if points && kind.iter().all(|&t| t == ShadowTarget::Point) {
            let columns = |v: &[Vec3]| Vec3x16::load(v, first);
            // Origin, its error bound, normal and target. (Not `array::map`: its closure may stay
            // out of the wide code.)
            let ends = Aligned([
                columns(&batch.position),
                columns(&batch.position_error),
                columns(&batch.normal),
                Vec3x16::load(target, 0),
            ]);
            let [origin, error, normal, to] = &ends.0;
            let [o, d] = spawn_rays_to_points_lanes([origin, error, normal], to);
            Aligned((o, d, F32x16::splat(1.0 - SHADOW_EPSILON)))
        } else {
            let mut s = Aligned((Vec3x16::ZERO, Vec3x16::ZERO, F32x16::ZERO));
            let (o, d, t) = &mut s.0;
            for l in 0..n {
                let ray = self.segment(first + l, kind[l], target[l], target_normal[l]);
                o.set_lane(l, ray.origin);
                d.set_lane(l, ray.dir);
                t[l] = ray.t_max;
            }
            s
        };
        let (o, d, t) = &segments.0;
        self.bvh.occluded_packet(o, d, t, n, &origins)
    }
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
