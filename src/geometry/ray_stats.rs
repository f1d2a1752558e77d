//! What a ray query costs in the wide tree's walk: nodes whose 8 boxes were tested, leaf blocks
//! visited and triangle lanes tested. Counted only with the feature `ray-stats` (off by default:
//! the counts cost a few percent of a ray), so that `examples/ray_throughput` and
//! `bench/mitsuba/rays.py` can show whether node tests, leaf tests or the rest bound a ray.

/// Counts since the last [`take`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayStats {
    /// Nodes whose child boxes were tested.
    pub nodes: u64,
    /// Leaf blocks whose primitives were tested.
    pub blocks: u64,
    /// Triangles tested (lanes of those blocks that hold a triangle).
    pub triangles: u64,
}

#[cfg(feature = "ray-stats")]
mod counting {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    use std::sync::{Arc, Mutex};

    use super::RayStats;

    /// One thread's counters, written by that thread alone (a load and a store, not a locked
    /// add) and summed by `take` from any thread.
    #[derive(Default)]
    pub(super) struct Counters([AtomicU64; 3]);

    static ALL: Mutex<Vec<Arc<Counters>>> = Mutex::new(Vec::new());

    thread_local! {
        static MINE: Arc<Counters> = {
            let c = Arc::new(Counters::default());
            ALL.lock().unwrap_or_else(|e| e.into_inner()).push(c.clone());
            c
        };
    }

    #[inline(always)]
    pub(super) fn add(which: usize, n: u64) {
        MINE.with(|c| c.0[which].store(c.0[which].load(Relaxed) + n, Relaxed));
    }

    pub(super) fn take_this_thread() -> RayStats {
        MINE.with(|c| RayStats {
            nodes: c.0[0].swap(0, Relaxed),
            blocks: c.0[1].swap(0, Relaxed),
            triangles: c.0[2].swap(0, Relaxed),
        })
    }

    pub(super) fn take() -> RayStats {
        let all = ALL.lock().unwrap_or_else(|e| e.into_inner());
        let sum = |i: usize| all.iter().map(|c| c.0[i].swap(0, Relaxed)).sum();
        RayStats { nodes: sum(0), blocks: sum(1), triangles: sum(2) }
    }
}

/// Whether this build counts (feature `ray-stats`).
pub const COUNTING: bool = cfg!(feature = "ray-stats");

/// The counts of every thread since the last call, reset to zero (all zero without the feature).
pub fn take() -> RayStats {
    #[cfg(feature = "ray-stats")]
    return counting::take();
    #[cfg(not(feature = "ray-stats"))]
    RayStats::default()
}

/// [`take`] of the calling thread's counts alone.
pub fn take_this_thread() -> RayStats {
    #[cfg(feature = "ray-stats")]
    return counting::take_this_thread();
    #[cfg(not(feature = "ray-stats"))]
    RayStats::default()
}

/// A node's boxes tested.
#[inline(always)]
pub(crate) fn node() {
    #[cfg(feature = "ray-stats")]
    counting::add(0, 1);
}

/// A leaf block visited, with `triangles` triangle lanes.
#[inline(always)]
pub(crate) fn block(triangles: u8) {
    #[cfg(feature = "ray-stats")]
    {
        counting::add(1, 1);
        counting::add(2, u64::from(triangles.count_ones()));
    }
    #[cfg(not(feature = "ray-stats"))]
    let _ = triangles;
}

#[cfg(all(test, feature = "ray-stats"))]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::{Mesh, Ray, SceneBvh};

    #[test]
    fn counts_what_a_walk_tests() {
        // A row of 64 unit triangles along x: more than a leaf, so the tree has inner nodes.
        let tris: Vec<[Vec3; 3]> = (0..64)
            .map(|i| {
                let x = 2.0 * i as f32;
                [Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)]
            })
            .collect();
        let mesh = Mesh::from_triangles(&tris).unwrap();
        let bvh = SceneBvh::of_mesh(&mesh);
        take_this_thread();
        // Misses the root's every child box: one node tested, no leaf.
        assert!(!bvh.occluded(&Ray::new(Vec3::new(0.2, 0.2, 5.0), Vec3::Z)));
        assert_eq!(take_this_thread(), RayStats { nodes: 1, blocks: 0, triangles: 0 });
        // Hits triangle 10: the walk reaches its leaf through at least one more node.
        let hit = bvh.closest_hit(&Ray::new(Vec3::new(20.2, 0.2, 5.0), -Vec3::Z)).unwrap();
        assert_eq!(hit.id.primitive, 10);
        let s = take_this_thread();
        assert!(s.nodes >= 2 && s.blocks >= 1 && s.triangles >= 1, "{s:?}");
        assert!(s.triangles <= 4 * s.blocks, "{s:?}");
    }
}
