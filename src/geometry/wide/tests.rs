//! The wide tree against the scalar tests and brute force.

use glam::Vec3;

use super::*;
use crate::geometry::triangle::ShearedRay;
use crate::geometry::{Mesh, SceneBvh};
use crate::rng::SplitMix64;

struct Triangles(Vec<[Vec3; 3]>);

impl LeafSource for Triangles {
    fn leaf_count(&self) -> usize {
        self.0.len()
    }
    fn triangle(&self, slot: usize) -> Option<[Vec3; 3]> {
        Some(self.0[slot])
    }
    fn bounds(&self, slot: usize) -> Aabb {
        let v = self.0[slot];
        Aabb::new(v[0].min(v[1]).min(v[2]).into(), v[0].max(v[1]).max(v[2]).into())
    }
}

fn v(rng: &mut SplitMix64, r: f32) -> Vec3 {
    Vec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
}

/// The lanes decide as the scalar watertight test, bit for bit: random triangles, and the
/// hard case of rays through a shared edge and a shared vertex (edge functions exactly zero,
/// where the lanes defer to the scalar test's f64 recomputation).
#[test]
fn triangle_lanes_match_the_scalar_test() {
    let mut rng = SplitMix64::new(5);
    let mut checked = [0usize; 2];
    for case in 0..4000 {
        let tris: Vec<[Vec3; 3]> = if case % 4 == 0 {
            // A fan around the origin: the ray down the z axis meets shared edges and vertices.
            let c = Vec3::new(0.0, 0.0, rng.range(-2.0, 2.0));
            (0..4)
                .map(|k| {
                    let a = k as f32 * std::f32::consts::FRAC_PI_2;
                    [
                        c,
                        c + Vec3::new(a.cos(), a.sin(), 0.0),
                        c + Vec3::new(
                            (a + std::f32::consts::FRAC_PI_2).cos(),
                            (a + std::f32::consts::FRAC_PI_2).sin(),
                            0.0,
                        ),
                    ]
                })
                .collect()
        } else {
            (0..1 + case % 4).map(|_| [v(&mut rng, 3.0), v(&mut rng, 3.0), v(&mut rng, 3.0)]).collect()
        };
        let ray = if case % 4 == 0 {
            Ray { origin: Vec3::new(0.0, 0.0, 5.0), dir: Vec3::NEG_Z, t_max: f32::INFINITY }
        } else {
            // Aimed near the first triangle, so that about half the rays hit something.
            let origin = v(&mut rng, 5.0);
            let aim = (tris[0][0] + tris[0][1] + tris[0][2]) / 3.0 + v(&mut rng, 0.5);
            Ray { origin, dir: aim - origin, t_max: rng.range(0.5, 2.0) }
        };
        let source = Triangles(tris.clone());
        let slots: Vec<u32> = (0..tris.len() as u32).collect();
        let block = make_block(&slots, &source);
        let sheared = ShearedRay::new(&ray);
        let (hit, exact, t, b) = triangle_block_hits(&block, &sheared, ray.t_max);
        for (l, tri) in tris.iter().enumerate() {
            let scalar = sheared.intersect(tri, ray.t_max);
            if exact & (1 << l) != 0 {
                checked[1] += 1;
                continue; // decided by the scalar test itself
            }
            let lane = (hit & (1 << l) != 0).then(|| (t[l], [b[0][l], b[1][l], b[2][l]]));
            assert_eq!(lane, scalar.map(|h| (h.t, h.b)), "case {case}, lane {l}");
            checked[0] += scalar.is_some() as usize;
        }
    }
    assert!(checked[0] > 200 && checked[1] > 100, "hits compared {}, exact lanes {}", checked[0], checked[1]);
}

/// Hard case: many triangles with one box (a binary leaf of more primitives than a block
/// holds) and a degenerate distribution (all on a line) still give the brute-force answers.
#[test]
fn stacked_and_collinear_triangles_match_brute_force() {
    let stacked: Vec<[Vec3; 3]> = (0..37).map(|_| [Vec3::ZERO, Vec3::X, Vec3::Y]).collect();
    let line: Vec<[Vec3; 3]> = (0..300)
        .map(|i| {
            let x = i as f32 * 0.01;
            [Vec3::new(x, 0.0, 0.0), Vec3::new(x + 0.005, 0.0, 0.0), Vec3::new(x, 0.005, 0.0)]
        })
        .collect();
    let mut rng = SplitMix64::new(9);
    for tris in [stacked, line] {
        let mesh = Mesh::from_triangles(&tris).unwrap();
        let bvh = SceneBvh::of_mesh(&mesh);
        for _ in 0..500 {
            let target = Vec3::new(rng.range(-0.1, 3.1), rng.range(-0.1, 1.1), 0.0);
            let origin = v(&mut rng, 4.0) + Vec3::Z * 5.0;
            let ray = Ray { origin, dir: target - origin, t_max: 1.5 };
            assert_eq!(bvh.closest_hit(&ray), bvh.closest_hit_brute_force(&ray), "{ray:?}");
            assert_eq!(bvh.occluded(&ray), bvh.occluded_brute_force(&ray), "{ray:?}");
        }
    }
}

/// Every child box of the collapsed tree is a box of the binary tree (collapsing only drops
/// nodes), so its cost is at most the binary tree's sum of half areas, and its blocks hold
/// every primitive once. A collapse that misread the binary tree's layout (obvhs's PLOC puts
/// parents after their children) packed large subtrees into made-up boxes and broke this.
#[test]
fn collapse_keeps_the_binary_trees_boxes_and_every_primitive() {
    use obvhs::BvhBuildParams;
    use obvhs::ploc::PlocBuilder;
    let mut rng = SplitMix64::new(3);
    let tris: Vec<[Vec3; 3]> = (0..5000)
        .map(|_| {
            let c = v(&mut rng, 50.0);
            [c, c + v(&mut rng, 0.5), c + v(&mut rng, 0.5)]
        })
        .collect();
    let source = Triangles(tris);
    let aabbs: Vec<Aabb> = (0..source.0.len()).map(|i| source.bounds(i)).collect();
    let p = BvhBuildParams::fast_build();
    let bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        p.ploc_search_distance,
        &aabbs,
        (0..aabbs.len() as u32).collect(),
        p.sort_precision,
        p.search_depth_threshold,
    );
    let identity: Vec<u32> = (0..aabbs.len() as u32).collect();
    let tree = WideBvh::from_bvh2(&bvh2, &identity, &source);
    let binary: f64 = bvh2.nodes.iter().map(|n| f64::from(n.aabb().half_area())).sum();
    assert!(tree.cost() <= binary * (1.0 + 1e-6), "collapsed cost {} > binary {binary}", tree.cost());
    let mut seen: Vec<u32> = tree.blocks.iter().flat_map(|b| b.slot).filter(|&s| s != NO_SLOT).collect();
    seen.sort_unstable();
    assert_eq!(seen, identity);
}
