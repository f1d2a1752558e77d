//! Irradiance volumes (`kelvin bake volume`): a voxel grid of ambient cubes, as Bevy's
//! `IrradianceVolume` samples them. Each voxel holds six values, one per axis direction: the
//! irradiance over pi about that direction at the voxel's centre (what a white Lambertian surface
//! facing it would reflect), linear sRGB, nit. Each is estimated by paths from the centre as from a
//! lightmap texel (`render::surface_paths`), so the light system, MIS and every bounce are the path
//! tracer's. A voxel whose samples mostly leak (their first ray meets a back face) lies inside
//! geometry; its sides, and any side without a valid sample, are filled from the same side of their
//! neighbours, ring by ring.
//!
//! Bevy's layout ([`IrradianceVolume::atlas`]): a 3D texture of (Rx, 2Ry, 3Rz) texels; side S of
//! voxel (x, y, z) at (x, y + Ry [S negative], z + Rz axis(S)). That is where Bevy's shader
//! (`irradiance_volume.wgsl`) reads a side: it offsets v by one half for a negative normal. (The doc
//! comment of Bevy's `irradiance_volume.rs` puts the positive sides in the upper half; the shader
//! is what renders.) The volume fills a 1 x 1 x 1 cube placed by the light probe's `Transform`
//! ([`IrradianceVolume::scale`], [`IrradianceVolume::center`]); voxel x's centre is at
//! (x + 1/2) / Rx of the cube's width.

use std::ops::RangeInclusive;

use glam::{IVec3, UVec3, Vec3};

use super::lightmap::Accumulator;
use super::parts::{self, BakePart, Part};
use super::{BakeError, BakedLight, Passes, Progress, TexelState, check_part, check_time, trace_all};
use crate::geometry::{GeometryId, Mesh, SceneBvh, SurfacePoint};
use crate::render::job::{self, LoadedJob};
use crate::render::path::PathDepth;
use crate::render::renderer::RenderStats;
use crate::render::surface_paths::{StartPoint, SurfaceTracer};

/// Accepted voxels per axis.
pub const RESOLUTION: RangeInclusive<u32> = 1..=128;

/// The six sides of a voxel, in the order of [`IrradianceVolume::sides`]: +X, -X, +Y, -Y, +Z, -Z.
pub const SIDES: [Vec3; 6] = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];

/// How to bake a volume.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeOptions {
    /// Voxels along x, y and z (each in [`RESOLUTION`]).
    pub resolution: UVec3,
    /// Paths per voxel side ([`job::SPP`]). Defaults to 256.
    pub spp: u32,
    /// Surfaces after the voxel's a path may reach, and where roulette may start.
    pub depth: PathDepth,
    /// All light or bounced light only. Defaults to all.
    pub light: BakedLight,
    /// The box the grid fills (min, max corners, m); None: the scene's geometry.
    pub bounds: Option<(Vec3, Vec3)>,
    /// Passes of `spp` paths per side until this many seconds have passed (at least one pass);
    /// None: one pass.
    pub time: Option<f64>,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        Self {
            resolution: UVec3::splat(8),
            spp: 256,
            depth: PathDepth::DEFAULT,
            light: BakedLight::All,
            bounds: None,
            time: None,
        }
    }
}

/// A baked irradiance volume.
#[derive(Clone, Debug, PartialEq)]
pub struct IrradianceVolume {
    /// Voxels along x, y and z.
    pub resolution: UVec3,
    /// The box the grid fills, m.
    pub min: Vec3,
    /// Its far corner, m.
    pub max: Vec3,
    /// Per voxel (x fastest, then y, then z) the six sides, in the order of [`SIDES`].
    pub sides: Vec<[Vec3; 6]>,
    /// Standard error of each baked side; zero for filled ones.
    pub std_error: Vec<[Vec3; 6]>,
    /// What each side holds.
    pub state: Vec<[TexelState; 6]>,
    /// Voxels found inside geometry (most of their samples leaked), filled from their neighbours.
    pub inside: usize,
    /// Time, paths, rays and the light system's report.
    pub stats: RenderStats,
}

impl IrradianceVolume {
    /// The voxel centre of voxel (x, y, z), m.
    pub fn voxel_center(&self, v: UVec3) -> Vec3 {
        self.min + (v.as_vec3() + 0.5) / self.resolution.as_vec3() * (self.max - self.min)
    }

    /// Translation of the light probe's `Transform`: the centre of the box.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Scale of the light probe's `Transform`: the box's size (Bevy's volume is a unit cube).
    pub fn scale(&self) -> Vec3 {
        self.max - self.min
    }

    /// The sides in Bevy's 3D texture layout (see the module's doc): (Rx, 2 Ry, 3 Rz) texels, x
    /// fastest, then y, then z.
    pub fn atlas(&self) -> Vec<Vec3> {
        let r = self.resolution.as_usizevec3();
        let (w, h) = (r.x, 2 * r.y);
        let mut atlas = vec![Vec3::ZERO; w * h * 3 * r.z];
        for (i, sides) in self.sides.iter().enumerate() {
            let (x, y, z) = (i % r.x, i / r.x % r.y, i / (r.x * r.y));
            for (s, value) in sides.iter().enumerate() {
                let (axis, negative) = (s / 2, s % 2 == 1);
                let (t, p) = (y + if negative { r.y } else { 0 }, z + axis * r.z);
                atlas[(p * h + t) * w + x] = *value;
            }
        }
        atlas
    }
}

/// Bakes an irradiance volume over `loaded`'s scene (see the module's doc).
pub fn bake_volume(
    loaded: &mut LoadedJob,
    opts: &VolumeOptions,
    progress: impl FnMut(Progress) + Send,
) -> Result<IrradianceVolume, BakeError> {
    let mut volume = empty_volume(loaded, opts)?;
    let (sums, stats) = trace(loaded, opts, &volume, Part::WHOLE, progress);
    volume.stats = stats;
    finish(&mut volume, &sums);
    Ok(volume)
}

/// Part `part` of [`bake_volume`]: the sums of its range of voxel sides (six per voxel, voxels x
/// fastest), every sample the whole bake would take of them, for [`merge_volume`].
pub fn bake_volume_part(
    loaded: &mut LoadedJob,
    opts: &VolumeOptions,
    part: Part,
    progress: impl FnMut(Progress) + Send,
) -> Result<BakePart, BakeError> {
    check_part(part, opts.time)?;
    let volume = empty_volume(loaded, opts)?;
    let (sums, stats) = trace(loaded, opts, &volume, part, progress);
    Ok(BakePart::new("volume", part, volume.sides.len() as u64 * 6, sums, &stats))
}

/// The volume of `parts` (every part of one bake of `loaded` with `opts`), bit for bit that of
/// [`bake_volume`] with the same options.
pub fn merge_volume(
    loaded: &mut LoadedJob,
    opts: &VolumeOptions,
    parts: Vec<BakePart>,
) -> Result<IrradianceVolume, BakeError> {
    let mut volume = empty_volume(loaded, opts)?;
    let (sums, stats) = parts::join("volume", volume.sides.len() as u64 * 6, parts)?;
    volume.stats = stats;
    finish(&mut volume, &sums);
    Ok(volume)
}

/// The world bounding box (min, max corners) of the meshes that nodes named `node` place: the box
/// a volume for that part of the scene fills. An error lists the names there are when no mesh is
/// placed by such a node (a node without a mesh has no extent to give).
pub fn node_bounds(loaded: &LoadedJob, node: &str) -> Result<(Vec3, Vec3), BakeError> {
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for p in loaded.primitives.iter().filter(|p| p.node_name.as_deref() == Some(node)) {
        let Some(mesh) = loaded.world.get::<Mesh>(p.entity) else { continue };
        for &q in mesh.positions() {
            bounds = Some(bounds.map_or((q, q), |(lo, hi)| (lo.min(q), hi.max(q))));
        }
    }
    match bounds {
        Some((lo, hi)) if lo.cmplt(hi).all() => Ok((lo, hi)),
        Some((lo, hi)) => Err(BakeError::Invalid(format!("node {node:?}: its meshes span {lo} to {hi}, no volume"))),
        None => {
            let mut names: Vec<&str> = loaded.primitives.iter().filter_map(|p| p.node_name.as_deref()).collect();
            names.dedup();
            Err(BakeError::Invalid(format!(
                "no mesh is placed by a node named {node:?}; nodes with meshes: {}",
                if names.is_empty() { "none named".to_owned() } else { names.join(", ") }
            )))
        }
    }
}

/// The volume `opts` asks for over `loaded`'s scene, with nothing baked.
fn empty_volume(loaded: &mut LoadedJob, opts: &VolumeOptions) -> Result<IrradianceVolume, BakeError> {
    for (axis, r) in ["x", "y", "z"].iter().zip(opts.resolution.to_array()) {
        if !RESOLUTION.contains(&r) {
            return Err(BakeError::Invalid(format!("resolution {axis} = {r} is outside 1..=128")));
        }
    }
    if !job::SPP.contains(&opts.spp) {
        return Err(BakeError::Invalid(format!("spp = {} is outside 1..=1048576", opts.spp)));
    }
    check_time(opts.time)?;
    if let Some((lo, hi)) = opts.bounds
        && !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all())
    {
        return Err(BakeError::Invalid(format!("bounds {lo} to {hi}: need finite corners with min < max")));
    }
    if opts.bounds.is_none() {
        // The scene BVH the bounds come from is built by the light system's first update.
        loaded.schedule.run(&mut loaded.world);
    }
    let Some((min, max)) = opts.bounds.or_else(|| loaded.world.resource::<SceneBvh>().world_bounds()) else {
        return Err(BakeError::NothingToBake("the scene has no geometry to bound the volume; give bounds".into()));
    };
    let voxels = opts.resolution.element_product() as usize;
    Ok(IrradianceVolume {
        resolution: opts.resolution,
        min,
        max,
        sides: vec![[Vec3::ZERO; 6]; voxels],
        std_error: vec![[Vec3::ZERO; 6]; voxels],
        state: vec![[TexelState::Empty; 6]; voxels],
        inside: 0,
        stats: RenderStats::default(),
    })
}

/// The sums of `part`'s voxel sides of `volume` and the stats of tracing them.
fn trace(
    loaded: &mut LoadedJob,
    opts: &VolumeOptions,
    volume: &IrradianceVolume,
    part: Part,
    progress: impl FnMut(Progress) + Send,
) -> (Vec<Accumulator>, RenderStats) {
    let LoadedJob { world, schedule, .. } = loaded;
    let cells = volume.sides.len() as u64 * 6;
    rayon::scope(|_| {
        let mut tracer = SurfaceTracer::new(world, schedule, opts.depth, opts.light == BakedLight::All, None);
        let r = opts.resolution;
        let place = |cell: u64, sample: u32| {
            let cell = cell as u32;
            let v = cell / 6;
            let voxel = UVec3::new(v % r.x, v / r.x % r.y, v / (r.x * r.y));
            let p = volume.voxel_center(voxel);
            // A point off any surface: its error bound is that of a point of unknown origin.
            let n = SIDES[(cell % 6) as usize];
            let p_error = SurfacePoint::from_point(p, n).p_error;
            StartPoint { p, p_error, ng: n, ns: n, geometry: GeometryId::NONE, pixel: cell, sample }
        };
        let passes = Passes { cells: part.range(cells), spp: opts.spp, time: opts.time };
        let (sums, spp) = trace_all(world, schedule, &mut tracer, passes, place, progress);
        (sums, RenderStats { spp: spp.into(), ..tracer.stats })
    })
}

/// Fills `volume`'s sides from their samples (`sums`, six per voxel), marks voxels inside geometry,
/// and fills what has no value from the same side of the neighbours.
fn finish(volume: &mut IrradianceVolume, sums: &[Accumulator]) {
    for (v, cells) in sums.chunks_exact(6).enumerate() {
        let (valid, leaked) = cells.iter().map(Accumulator::counts).fold((0, 0), |a, c| (a.0 + c.0, a.1 + c.1));
        // Inside closed geometry every ray meets a back face; in front of a wall seen from behind,
        // at most about half do.
        if leaked > valid {
            volume.inside += 1;
            continue;
        }
        for (s, c) in cells.iter().enumerate() {
            if let Some((mean, error)) = c.mean() {
                (volume.sides[v][s], volume.std_error[v][s], volume.state[v][s]) = (mean, error, TexelState::Baked);
            }
        }
    }
    let r = volume.resolution.as_ivec3();
    let index = |p: IVec3| (p.x + r.x * (p.y + r.y * p.z)) as usize;
    let neighbours = SIDES.map(|d| d.as_ivec3());
    loop {
        let mut ring = Vec::new();
        for v in 0..volume.sides.len() {
            let p = IVec3::new(v as i32 % r.x, v as i32 / r.x % r.y, v as i32 / (r.x * r.y));
            for s in 0..6 {
                if volume.state[v][s] != TexelState::Empty {
                    continue;
                }
                let (mut sum, mut n) = (Vec3::ZERO, 0);
                for q in neighbours.map(|d| p + d) {
                    let inside = q.cmpge(IVec3::ZERO).all() && q.cmplt(r).all();
                    if inside && volume.state[index(q)][s] != TexelState::Empty {
                        (sum, n) = (sum + volume.sides[index(q)][s], n + 1);
                    }
                }
                if n > 0 {
                    ring.push((v, s, sum / n as f32));
                }
            }
        }
        if ring.is_empty() {
            break;
        }
        for (v, s, value) in ring {
            (volume.sides[v][s], volume.state[v][s]) = (value, TexelState::Filled);
        }
    }
}
