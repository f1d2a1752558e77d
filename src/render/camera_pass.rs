//! The camera pass: a batch's camera rays and their closest hits, written straight into the
//! `ShadingBatch` (one slot per camera sample, hit or not) and the renderer's own columns. No
//! per-sample record is copied on: the light system and the shading pass read these columns.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::bsdf::bent_shading_normal;
use super::camera::CameraModel;
use crate::geometry::{GeometryId, Hit, HitSink, RAY_CHUNK, SceneBvh};
use crate::lanes::{F32x16, LANES, Vec3x16};
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

/// Writes slot `i` of every column for a ray with direction `dir` and closest hit `hit`. Escaped
/// rays get a NaN position (the light system chooses no light there) and zero normals.
#[inline(always)]
fn write_slot(batch: &mut BatchChunk, i: usize, dir: Vec3, hit: Option<Hit>) {
    let Some(h) = hit else {
        (batch.position[i], batch.position_error[i]) = (Vec3::NAN, Vec3::ZERO);
        (batch.normal[i], batch.shading_normal[i]) = (Vec3::ZERO, Vec3::ZERO);
        batch.geometry[i] = GeometryId::NONE;
        batch.set_surface(i, dir, SampleSurface::ESCAPED);
        return;
    };
    // Normals face the viewer.
    let flipped = h.ng.dot(dir) > 0.0;
    let flip = if flipped { -1.0 } else { 1.0 };
    // The shading normal goes to the geometric one's side (`ns . ng` does not change sign when
    // both turn): one whose file disagrees with the winding is turned over, not flattened.
    let ns = if h.ns.dot(h.ng) < 0.0 { -h.ns * flip } else { h.ns * flip };
    let ns = bent_shading_normal(ns, h.ng * flip, -dir);
    (batch.position[i], batch.position_error[i]) = (h.p, h.p_error);
    (batch.normal[i], batch.shading_normal[i]) = (h.ng * flip, ns);
    batch.geometry[i] = h.id;
    let surface =
        SampleSurface { uv: h.uv, material: h.material, instance: h.instance, primitive: h.id.primitive, flipped };
    batch.set_surface(i, dir, surface);
}

/// Writes the closest hits of the block of camera rays from slot `b` of a chunk.
struct SlotWriter<'c, 'a> {
    chunk: &'c mut BatchChunk<'a>,
    b: usize,
    /// Lanes that are samples (the chunk's last block may be partial).
    n: usize,
    dirs: &'c Vec3x16,
}

impl HitSink for SlotWriter<'_, '_> {
    #[inline(always)]
    fn hit(&mut self, l: usize, hit: Option<Hit>) {
        if l < self.n {
            write_slot(self.chunk, self.b + l, self.dirs.lane(l), hit);
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

impl BatchChunk<'_> {
    /// Writes slot `i` of the `CameraColumns`.
    #[inline(always)]
    fn set_surface(&mut self, i: usize, dir: Vec3, surface: SampleSurface) {
        for a in 0..3 {
            self.dir[a][i] = dir[a];
        }
        (self.uv[0][i], self.uv[1][i]) = surface.uv.into();
        (self.material[i], self.instance[i]) = (surface.material, surface.instance);
        self.flipped[i] = surface.flipped;
    }
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
        let first = c * RAY_CHUNK;
        for (i, s) in surfaces[first..first + chunk.pixel.len()].iter().enumerate() {
            (chunk.pixel[i], chunk.sample[i]) = (s.pixel, s.sample);
            write_slot(chunk, i, s.dir, Some(s.hit));
        }
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
        let mut writer = SlotWriter { chunk: &mut *chunk, b, n: end - b, dirs: &dirs };
        bvh.closest_hits_packet(&origins, &dirs, &F32x16::splat(f32::INFINITY), end - b, &mut writer);
        b = end;
    }
}
