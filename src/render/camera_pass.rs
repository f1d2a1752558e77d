//! The camera pass: a batch's camera rays and their closest hits, written straight into the
//! `ShadingBatch` (one slot per camera sample, hit or not) and the renderer's own columns. No
//! per-sample record is copied on: the light system and the shading pass read these columns.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::bsdf::{bent_shading_normal, shading_normal_stands};
use super::camera::CameraModel;
use crate::geometry::{GeometryId, Hit, HitLanes, RAY_CHUNK, SceneBvh};
use crate::lanes::{F32x16, LANES, U32x16, Vec3x16};
use crate::rng::{Pattern, SampleStream};
use crate::shading::{ImageLayout, ShadingBatch};

/// What shading needs of a camera sample's surface besides its `ShadingBatch` slot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SampleSurface {
    pub(super) uv: Vec2,
    pub(super) material: u32,
    /// BVH instance that was hit; `ESCAPED` for rays that hit nothing.
    pub(super) instance: u32,
    pub(super) primitive: u32,
    /// The batch's normal is the hit's geometric normal negated (so that it faces the camera).
    pub(super) flipped: bool,
}

impl SampleSurface {
    pub(super) const ESCAPED: Self =
        Self { uv: Vec2::ZERO, material: 0, instance: u32::MAX, primitive: 0, flipped: false };
}

/// The renderer's per-sample columns, indexed like the `ShadingBatch`: one column per field and
/// axis, so that the camera pass stores and the shading pass loads whole lanes (a column of
/// `SampleSurface` records was built lane by lane and interleaved). The primitive hit is the
/// batch's own `geometry` column.
#[derive(Default)]
pub(super) struct CameraColumns {
    /// Unit direction of the camera ray, x, y and z.
    pub(super) dir: [Vec<f32>; 3],
    pub(super) uv: [Vec<f32>; 2],
    pub(super) material: Vec<u32>,
    /// BVH instance that was hit; `u32::MAX` (as `SampleSurface::ESCAPED`) for rays that hit nothing.
    pub(super) instance: Vec<u32>,
    /// See [`SampleSurface::flipped`].
    pub(super) flipped: Vec<bool>,
}

impl CameraColumns {
    /// Sizes every column to `n` slots, keeping what they held.
    pub(super) fn resize(&mut self, n: usize) {
        for column in self.dir.iter_mut().chain(&mut self.uv) {
            column.resize(n, 0.0);
        }
        for column in [&mut self.material, &mut self.instance] {
            column.resize(n, 0);
        }
        self.flipped.resize(n, false);
    }

    /// The direction of sample `k`'s camera ray.
    #[inline(always)]
    pub(super) fn dir(&self, k: usize) -> Vec3 {
        Vec3::new(self.dir[0][k], self.dir[1][k], self.dir[2][k])
    }

    /// Whether sample `k`'s camera ray hit nothing.
    #[inline(always)]
    pub(super) fn escaped(&self, k: usize) -> bool {
        self.instance[k] == SampleSurface::ESCAPED.instance
    }

    /// Sample `k`'s surface, on primitive `primitive` (the batch's `geometry[k].primitive`).
    #[inline(always)]
    pub(super) fn surface(&self, k: usize, primitive: u32) -> SampleSurface {
        SampleSurface {
            uv: Vec2::new(self.uv[0][k], self.uv[1][k]),
            material: self.material[k],
            instance: self.instance[k],
            primitive,
            flipped: self.flipped[k],
        }
    }
}

/// Which samples a batch holds and how they map to pixels: sample index k is sample
/// `first_sample + k % spp` of pixel k / spp of `region` (row-major), so a pixel's samples are
/// adjacent. Rays and random streams take the pixel's place in the full image, whose rows are
/// `full_width` long.
#[derive(Clone, Copy)]
pub(super) struct SampleRange {
    pub(super) first: usize,
    pub(super) len: usize,
    pub(super) region: super::tiles::Crop,
    pub(super) full_width: u32,
    pub(super) spp: u32,
    pub(super) seed: u64,
    pub(super) pattern: Pattern,
    /// Samples of each pixel that earlier passes took.
    pub(super) first_sample: u32,
}

/// Writes slots `b..b + n` of every column for a block of rays with unit directions `dirs` and
/// closest hits `hits`, in lanes. Escaped rays get a NaN position (the light system chooses no
/// light there) and zero normals.
#[inline(always)]
fn write_block(batch: &mut BatchChunk, b: usize, n: usize, dirs: &Vec3x16, hits: &HitLanes) {
    let found = hits.found;
    // Normals face the viewer.
    let flipped = hits.ng.dot(*dirs).gt(F32x16::ZERO) & found;
    let flip = F32x16::select(flipped, F32x16::splat(-1.0), F32x16::ONE);
    let ng = hits.ng * flip;
    // The shading normal goes to the geometric one's side (`ns . ng` does not change sign when
    // both turn): one whose file disagrees with the winding is turned over, not flattened.
    let mut ns = Vec3x16::select(hits.ns.dot(hits.ng).lt(F32x16::ZERO), -hits.ns * flip, hits.ns * flip);
    let wo = -*dirs;
    let mut bend = (!shading_normal_stands(ns, ng, wo) & found).bits() & (u32::MAX >> (LANES - n));
    while bend != 0 {
        let l = bend.trailing_zeros() as usize;
        bend &= bend - 1;
        ns.set_lane(l, bent_shading_normal(ns.lane(l), ng.lane(l), wo.lane(l)));
    }
    let none = GeometryId::NONE;
    store_vec3s(batch.position, b, n, Vec3x16::select(found, hits.p, Vec3x16::splat(Vec3::NAN)));
    store_vec3s(batch.position_error, b, n, Vec3x16::select(found, hits.p_error, Vec3x16::ZERO));
    store_vec3s(batch.normal, b, n, Vec3x16::select(found, ng, Vec3x16::ZERO));
    store_vec3s(batch.shading_normal, b, n, Vec3x16::select(found, ns, Vec3x16::ZERO));
    let entity_index = U32x16::select(found, hits.entity_index, U32x16::splat(none.entity_index));
    let primitive = U32x16::select(found, hits.primitive, U32x16::splat(none.primitive));
    for l in 0..n {
        batch.geometry[b + l] = GeometryId { entity_index: entity_index.0[l], primitive: primitive.0[l] };
    }
    for (a, dir) in dirs.as_array().iter().enumerate() {
        store(batch.dir[a], b, n, dir.0);
    }
    for (a, uv) in hits.uv.iter().enumerate() {
        store(batch.uv[a], b, n, F32x16::select(found, *uv, F32x16::ZERO).0);
    }
    store(batch.material, b, n, U32x16::select(found, hits.material, U32x16::splat(0)).0);
    let escaped = SampleSurface::ESCAPED.instance;
    store(batch.instance, b, n, U32x16::select(found, hits.instance, U32x16::splat(escaped)).0);
    store(batch.flipped, b, n, flipped.to_bools());
}

/// Stores the first `n` lanes at `column[b..]`: a whole block as one copy of known length (a
/// vector store; a variable one calls memmove).
#[inline(always)]
fn store<T: Copy>(column: &mut [T], b: usize, n: usize, lanes: [T; LANES]) {
    if n == LANES {
        column[b..b + LANES].copy_from_slice(&lanes);
    } else {
        column[b..b + n].copy_from_slice(&lanes[..n]);
    }
}

/// [`store`] for vectors.
#[inline(always)]
fn store_vec3s(column: &mut [Vec3], b: usize, n: usize, lanes: Vec3x16) {
    if n == LANES {
        lanes.store_vec3s((&mut column[b..b + LANES]).try_into().expect("a block of LANES slots"));
    } else {
        for l in 0..n {
            column[b + l] = lanes.lane(l);
        }
    }
}

/// One `RAY_CHUNK` of every column the camera pass writes.
struct BatchChunk<'a> {
    position: &'a mut [Vec3],
    position_error: &'a mut [Vec3],
    normal: &'a mut [Vec3],
    shading_normal: &'a mut [Vec3],
    pixel: &'a mut [u32],
    sample: &'a mut [u32],
    geometry: &'a mut [GeometryId],
    dir: [&'a mut [f32]; 3],
    uv: [&'a mut [f32]; 2],
    material: &'a mut [u32],
    instance: &'a mut [u32],
    flipped: &'a mut [bool],
}

/// Traces the camera rays of `range` and writes every slot of `batch` (resized to `range.len`,
/// wavelengths left empty, geometry filled) and of `columns`. Random numbers (dimensions 1 and 2
/// of each sample's stream) and rays are computed in lanes, hits in packets of `LANES` rays.
pub(super) fn trace_camera_rays(
    batch: &mut ShadingBatch,
    columns: &mut CameraColumns,
    bvh: &SceneBvh,
    camera: &CameraModel,
    range: SampleRange,
) {
    // Slot i is sample (first + i) % spp of region pixel (first + i) / spp: an image, for
    // spatial reservoir reuse.
    let layout = ImageLayout { width: range.region.width(), samples_per_pixel: range.spp, first: range.first as u64 };
    batch.layout = Some(layout);
    for_each_chunk(batch, columns, range.len, |c, chunk| {
        crate::lanes::widest(
            #[inline(always)]
            || trace_chunk(chunk, range.first + c * RAY_CHUNK, bvh, camera, range),
        )
    });
}

/// A surface a ray found, with the sample whose path it continues.
#[derive(Clone, Copy)]
pub(super) struct FoundSurface {
    /// Unit direction of the ray.
    pub(super) dir: Vec3,
    pub(super) hit: Hit,
    pub(super) pixel: u32,
    pub(super) sample: u32,
}

/// Writes slot `i` of `batch` (resized, wavelengths left empty) and `columns` for surface `i`
/// of `surfaces`, as the camera pass writes a hit: the path tracer's next bounce.
pub(super) fn write_found_surfaces(batch: &mut ShadingBatch, columns: &mut CameraColumns, surfaces: &[FoundSurface]) {
    // The surviving paths' surfaces are no image.
    batch.layout = None;
    for_each_chunk(batch, columns, surfaces.len(), |c, chunk| {
        let surfaces = &surfaces[c * RAY_CHUNK..c * RAY_CHUNK + chunk.pixel.len()];
        crate::lanes::widest(
            #[inline(always)]
            || {
                let (mut hits, mut dirs) = (HitLanes::default(), Vec3x16::ZERO);
                for (k, block) in surfaces.chunks(LANES).enumerate() {
                    for (l, s) in block.iter().enumerate() {
                        let i = k * LANES + l;
                        (chunk.pixel[i], chunk.sample[i]) = (s.pixel, s.sample);
                        hits.set(l, Some(s.hit));
                        dirs.set_lane(l, s.dir);
                    }
                    write_block(chunk, k * LANES, block.len(), &dirs, &hits);
                }
            },
        )
    });
}

/// Sizes `batch` (wavelengths emptied) and `columns` to `n` slots and calls `write` on each
/// `RAY_CHUNK` of them in parallel, with the chunk's index.
fn for_each_chunk(
    batch: &mut ShadingBatch,
    columns: &mut CameraColumns,
    n: usize,
    write: impl Fn(usize, &mut BatchChunk) + Sync,
) {
    batch.set_len(n);
    columns.resize(n);
    let CameraColumns { dir: [dx, dy, dz], uv: [u, v], material, instance, flipped } = columns;
    let chunks = (
        (
            batch.position.par_chunks_mut(RAY_CHUNK),
            batch.position_error.par_chunks_mut(RAY_CHUNK),
            batch.normal.par_chunks_mut(RAY_CHUNK),
            batch.shading_normal.par_chunks_mut(RAY_CHUNK),
            batch.pixel.par_chunks_mut(RAY_CHUNK),
            batch.sample.par_chunks_mut(RAY_CHUNK),
            batch.geometry.par_chunks_mut(RAY_CHUNK),
        ),
        (
            dx.par_chunks_mut(RAY_CHUNK),
            dy.par_chunks_mut(RAY_CHUNK),
            dz.par_chunks_mut(RAY_CHUNK),
            u.par_chunks_mut(RAY_CHUNK),
            v.par_chunks_mut(RAY_CHUNK),
            material.par_chunks_mut(RAY_CHUNK),
            instance.par_chunks_mut(RAY_CHUNK),
            flipped.par_chunks_mut(RAY_CHUNK),
        ),
    );
    chunks.into_par_iter().enumerate().for_each(|(c, (batch, columns))| {
        let (position, position_error, normal, shading_normal, pixel, sample, geometry) = batch;
        let (dx, dy, dz, u, v, material, instance, flipped) = columns;
        let mut chunk = BatchChunk {
            position,
            position_error,
            normal,
            shading_normal,
            pixel,
            sample,
            geometry,
            dir: [dx, dy, dz],
            uv: [u, v],
            material,
            instance,
            flipped,
        };
        write(c, &mut chunk);
    });
}

/// [`trace_camera_rays`] for one chunk whose first sample has index `first`.
#[inline(always)]
fn trace_chunk(chunk: &mut BatchChunk, first: usize, bvh: &SceneBvh, camera: &CameraModel, range: SampleRange) {
    let SampleRange { region, full_width, spp, seed, pattern, .. } = range;
    // Counters walk the pixels (in full-image coordinates) and samples: one division per chunk,
    // not per sample.
    let (tile_pixel, mut next_sample) = ((first / spp as usize) as u32, (first % spp as usize) as u32);
    let (width, x0) = (region.width(), region.x0);
    let (mut next_x, mut next_y) = (x0 + tile_pixel % width, region.y0 + tile_pixel / width);
    let mut next_pixel = next_y * full_width + next_x;
    // The step from a row's last pixel to the next row's first.
    let row_step = full_width - width;
    let len = chunk.pixel.len();
    let origin = camera.origin();
    let origins = Vec3x16::splat(origin);
    let mut hits = HitLanes::default();
    let mut b = 0;
    while b < len {
        let end = (b + LANES).min(len);
        let (mut pixel, mut sample) = ([0u32; LANES], [0u32; LANES]);
        let (mut x, mut y) = ([0u32; LANES], [0u32; LANES]);
        let one_pixel = end - b == LANES && next_sample as usize + LANES <= spp as usize;
        let first_pixel = next_pixel;
        if one_pixel {
            // A whole block of one pixel's samples (any spp of 16 or more): whole lanes of one
            // value, where the loop below would store lane by lane and stall the vector loads.
            (pixel, x, y) = ([next_pixel; LANES], [next_x; LANES], [next_y; LANES]);
            for (l, s) in sample.iter_mut().enumerate() {
                *s = range.first_sample + next_sample + l as u32;
            }
            next_sample += LANES as u32;
            if next_sample == spp {
                (next_pixel, next_sample, next_x) = (next_pixel + 1, 0, next_x + 1);
                if next_x == region.x1 {
                    (next_x, next_y, next_pixel) = (x0, next_y + 1, next_pixel + row_step);
                }
            }
        } else {
            for l in 0..end - b {
                (pixel[l], sample[l], x[l], y[l]) = (next_pixel, range.first_sample + next_sample, next_x, next_y);
                next_sample += 1;
                if next_sample == spp {
                    (next_pixel, next_sample, next_x) = (next_pixel + 1, 0, next_x + 1);
                    if next_x == region.x1 {
                        (next_x, next_y, next_pixel) = (x0, next_y + 1, next_pixel + row_step);
                    }
                }
            }
        }
        // A copy of a length known at compile time is a vector store; a variable one calls memmove.
        if end - b == LANES {
            chunk.pixel[b..end].copy_from_slice(&pixel);
            chunk.sample[b..end].copy_from_slice(&sample);
        } else {
            chunk.pixel[b..end].copy_from_slice(&pixel[..end - b]);
            chunk.sample[b..end].copy_from_slice(&sample[..end - b]);
        }
        // (Reading `pixel` back to find it is one pixel stalled on its stores.)
        // The pixel offset is the 2D draw of the stream's first set (dimensions 1, 2).
        let [_, u, v] = if one_pixel {
            SampleStream::pixel_lanes::<3>(pattern, seed, first_pixel, &sample)
        } else {
            SampleStream::lanes::<3>(pattern, seed, &pixel, &sample)
        };
        let dirs = camera.dirs_lanes([&x, &y], &u, &v);
        bvh.closest_hits_packet(&origins, &dirs, &F32x16::splat(f32::INFINITY), end - b, &mut hits);
        write_block(chunk, b, end - b, &dirs, &hits);
        b = end;
    }
}
