//! Traces a file of rays against a glTF file's scene BVH and prints closest-hit and any-hit rays
//! per second, one ray at a time in parallel batches and as 16-ray packets, as JSON. Closest hits
//! are timed twice one ray at a time: with their records (`closest_hits`, an `Option<Hit>` per
//! ray) and without (`closest_hit_ref`, a hit-or-miss flag per ray, what Mitsuba's
//! `ray_intersect_preliminary(..).is_valid()` evaluates). The rays
//! file holds little-endian f32 records (origin xyz, direction xyz, t_max); `bench/mitsuba/rays.py`
//! writes it and traces the same rays with Mitsuba.
//! `cargo run --release --example ray_throughput -- SCENE.glb RAYS.f32 [repeats [query]]`; with a query
//! (closest, closest_ref, any, closest_packet, any_packet) it runs that one `repeats` times and prints
//! nothing, for a profiler.

use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::{
    GeometryId, HitLanes, RAY_CHUNK, Ray, SceneBvh, closest_hits, occluded, ray_columns, ray_stats,
};
use kelvin::lanes::{self, LANES};
use kelvin::systems::LightingPlugin;
use rayon::prelude::*;

fn read_rays(path: &str) -> Result<Vec<Ray>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    if bytes.len() % 28 != 0 {
        return Err(format!("{path}: {} bytes is not a whole number of 28-byte rays", bytes.len()));
    }
    let f = |c: &[u8], i: usize| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().expect("4 bytes"));
    Ok(bytes
        .chunks_exact(28)
        .map(|c| Ray {
            origin: Vec3::new(f(c, 0), f(c, 1), f(c, 2)),
            dir: Vec3::new(f(c, 3), f(c, 4), f(c, 5)),
            t_max: f(c, 6),
        })
        .collect())
}

/// Best of `repeats` timings of `run`, in seconds, and what the last run returned.
fn best<T>(repeats: usize, mut run: impl FnMut() -> T) -> (f64, T) {
    let mut out = run(); // warm-up
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let t = Instant::now();
        out = run();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out)
}

/// Whether each ray hits something, from `closest_hit_ref` (the closest hit without its record).
fn closest_refs(bvh: &SceneBvh, rays: &[Ray], out: &mut Vec<bool>) {
    rays.par_iter().with_min_len(RAY_CHUNK).map(|r| bvh.closest_hit_ref(r).is_some()).collect_into_vec(out);
}

fn packet_hits(bvh: &SceneBvh, rays: &[Ray]) -> usize {
    rays.par_chunks(LANES * 256)
        .map(|chunk| {
            lanes::widest(
                #[inline(always)]
                || {
                    let (mut hits, mut out) = (0, HitLanes::default());
                    for packet in chunk.chunks(LANES) {
                        let (o, d, t) = ray_columns(packet);
                        bvh.closest_hits_packet(&o, &d, &t, packet.len(), &mut out);
                        hits += out.found.bits().count_ones() as usize;
                    }
                    hits
                },
            )
        })
        .sum()
}

fn packet_blocked(bvh: &SceneBvh, rays: &[Ray]) -> usize {
    rays.par_chunks(LANES * 256)
        .map(|chunk| {
            lanes::widest(
                #[inline(always)]
                || {
                    let mut blocked = 0;
                    for packet in chunk.chunks(LANES) {
                        let (o, d, t) = ray_columns(packet);
                        let mask = bvh.occluded_packet(&o, &d, &t, packet.len(), &[GeometryId::NONE; LANES]);
                        blocked += mask.count_ones() as usize;
                    }
                    blocked
                },
            )
        })
        .sum()
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, rays_path, ..] = args.as_slice() else {
        return Err("usage: ray_throughput SCENE.glb RAYS.f32 [repeats [query]]".into());
    };
    let repeats = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(5);
    let rays = read_rays(rays_path)?;
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    kelvin::render::scene_file::spawn_gltf_file(&mut world, std::path::Path::new(scene)).map_err(|e| e.to_string())?;
    schedule.run(&mut world);
    let bvh = world.resource::<SceneBvh>();
    let (mut hit_buf, mut occ_buf) = (Vec::new(), Vec::new());
    if let Some(query) = args.get(3) {
        // One query, `repeats` times, for a profiler or an instruction counter (cachegrind).
        for _ in 0..repeats {
            match query.as_str() {
                "closest" => closest_hits(bvh, &rays, &mut hit_buf),
                "closest_ref" => closest_refs(bvh, &rays, &mut occ_buf),
                "any" => occluded(bvh, &rays, &mut occ_buf),
                "closest_packet" => drop(packet_hits(bvh, &rays)),
                "any_packet" => drop(packet_blocked(bvh, &rays)),
                _ => {
                    return Err(format!(
                        "unknown query {query}: closest, closest_ref, any, closest_packet, any_packet"
                    ));
                }
            }
        }
        return Ok(());
    }
    let (closest_s, hits) = best(repeats, || {
        closest_hits(bvh, &rays, &mut hit_buf);
        hit_buf.iter().filter(|h| h.is_some()).count()
    });
    let (closest_ref_s, ref_hits) = best(repeats, || {
        closest_refs(bvh, &rays, &mut occ_buf);
        occ_buf.iter().filter(|&&h| h).count()
    });
    let (any_s, blocked) = best(repeats, || {
        occluded(bvh, &rays, &mut occ_buf);
        occ_buf.iter().filter(|&&b| b).count()
    });
    let (closest_packet_s, packet_hit_count) = best(repeats, || packet_hits(bvh, &rays));
    let (any_packet_s, packet_blocked_count) = best(repeats, || packet_blocked(bvh, &rays));
    if (hits, hits, blocked) != (packet_hit_count, ref_hits, packet_blocked_count) {
        return Err(format!(
            "queries disagree: hits {hits} vs {packet_hit_count} (packets) and {ref_hits} (without records), \
             blocked {blocked} vs {packet_blocked_count}"
        ));
    }
    let n = rays.len() as f64;
    // What one ray costs in the walk (feature `ray-stats`): one untimed run of each single-ray query.
    let per_ray = |run: &mut dyn FnMut()| {
        ray_stats::take();
        run();
        let s = ray_stats::take();
        format!(
            "{{\"nodes\": {:.2}, \"blocks\": {:.2}, \"triangles\": {:.2}}}",
            s.nodes as f64 / n,
            s.blocks as f64 / n,
            s.triangles as f64 / n
        )
    };
    // A fingerprint of every closest hit's t bits, ray by ray, so two builds can be checked to
    // return the same hits bit for bit.
    let t_bits: u64 = rays
        .par_iter()
        .enumerate()
        .map(|(i, r)| {
            let bits = bvh.closest_hit_ref(r).map_or(u64::MAX, |h| u64::from(h.t().to_bits()));
            bits.wrapping_mul(2 * i as u64 + 1).rotate_left(i as u32 % 64)
        })
        .reduce(|| 0, u64::wrapping_add);
    let stats = if ray_stats::COUNTING {
        let closest = per_ray(&mut || closest_refs(bvh, &rays, &mut occ_buf));
        let any = per_ray(&mut || occluded(bvh, &rays, &mut occ_buf));
        format!(", \"closest_walk\": {closest}, \"any_walk\": {any}")
    } else {
        String::new()
    };
    println!(
        "{{\"rays\": {}, \"hits\": {hits}, \"blocked\": {blocked}, \"t_bits\": \"{t_bits:016x}\", \"threads\": {}, \"closest_per_s\": {:.0}, \"closest_ref_per_s\": {:.0}, \"any_per_s\": {:.0}, \"closest_packet_per_s\": {:.0}, \"any_packet_per_s\": {:.0}{stats}}}",
        rays.len(),
        rayon::current_num_threads(),
        n / closest_s,
        n / closest_ref_s,
        n / any_s,
        n / closest_packet_s,
        n / any_packet_s
    );
    Ok(())
}
