//! The traversal form of the light BVH: the binary tree collapsed two levels at a time into
//! nodes of up to four slots, stored as structure-of-arrays lanes so one SIMD pass computes all
//! four importances. Half the depth and a quarter of the dependent importance chains of the
//! binary walk: the binary tree stays the source of truth (build, refit, cost), and every slot
//! is a copy of one binary node's bounds, updated when that node is refitted.

use glam::{BVec4A, Vec3, Vec4};

use super::bvh_build::Node;
use super::importance::{ClusterQuery, EMPTY_BOUNDS};
use super::importance_lanes::{self, ClusterLanes};
use crate::lanes::{F32x16, Mask16, Vec3x16};
use crate::light::{LightId, LightKind};

/// Marks "no slot" in `slot_of` and "no parent" for the root.
pub(super) const NONE: u32 = u32::MAX;

/// Up to four clusters side by side, one per SIMD lane. Empty lanes have zero power.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub(super) struct WideNode {
    min: [Vec4; 3],
    max: [Vec4; 3],
    w: [Vec4; 3],
    phi: Vec4,
    radius: Vec4,
    cos_theta_o: Vec4,
    sin_theta_o: Vec4,
    cos_theta_e: Vec4,
    /// 1 in the lanes of two-sided clusters.
    two_sided: Vec4,
    /// Per lane: a light's row (leaf lanes) or the wide node below (interior lanes).
    pub child: [u32; 4],
    /// Per lane: the light's kind for leaf lanes; None for interior and empty lanes.
    pub kind: [Option<LightKind>; 4],
    /// The binary node this wide node was collapsed from (its slot in the parent gives the way up).
    pub origin: u32,
}

impl WideNode {
    fn empty(origin: u32) -> Self {
        let mut n = Self {
            min: [Vec4::ZERO; 3],
            max: [Vec4::ZERO; 3],
            w: [Vec4::ZERO; 3],
            phi: Vec4::ZERO,
            radius: Vec4::ZERO,
            cos_theta_o: Vec4::ZERO,
            sin_theta_o: Vec4::ZERO,
            cos_theta_e: Vec4::ZERO,
            two_sided: Vec4::ZERO,
            child: [NONE; 4],
            kind: [None; 4],
            origin,
        };
        let empty = ClusterQuery::from(&EMPTY_BOUNDS);
        for lane in 0..4 {
            n.set_lane(lane, &empty);
        }
        n
    }

    /// Writes the cluster `q` into `lane`.
    pub fn set_lane(&mut self, lane: usize, q: &ClusterQuery) {
        for axis in 0..3 {
            self.min[axis][lane] = q.min[axis];
            self.max[axis][lane] = q.max[axis];
            self.w[axis][lane] = q.w[axis];
        }
        self.phi[lane] = q.phi;
        self.radius[lane] = q.signed_radius.abs();
        self.cos_theta_o[lane] = q.cos_theta_o;
        self.sin_theta_o[lane] = q.sin_theta_o;
        self.cos_theta_e[lane] = q.cos_theta_e;
        self.two_sided[lane] = if q.two_sided() { 1.0 } else { 0.0 };
    }

    /// The light in `lane`, for leaf lanes.
    #[inline]
    pub fn light(&self, lane: usize) -> Option<LightId> {
        self.kind[lane].map(|kind| LightId { kind, row: self.child[lane] })
    }

    /// The four importances at `p` with normal `n` (zero for no normal): lane by lane the same
    /// formula as `ClusterQuery::importance` (see there for the model and its sources).
    #[inline(always)]
    pub fn importance(&self, p: Vec3, n: Vec3) -> Vec4 {
        let has_n = BVec4A::splat(n != Vec3::ZERO);
        importance_lanes::importance(&self.lanes(), p.to_array().map(Vec4::splat), n.to_array().map(Vec4::splat), has_n)
    }

    /// The clusters as lanes.
    #[inline(always)]
    fn lanes(&self) -> ClusterLanes<Vec4> {
        ClusterLanes {
            min: self.min,
            max: self.max,
            w: self.w,
            phi: self.phi,
            radius: self.radius,
            cos_theta_o: self.cos_theta_o,
            sin_theta_o: self.sin_theta_o,
            cos_theta_e: self.cos_theta_e,
            two_sided: self.two_sided,
        }
    }

    /// Cluster `c` seen from `LANES` points (`p`, `n` as lane columns; `has_n`: lanes with a
    /// normal): the same bits as lane `c` of [`Self::importance`] at each point.
    #[inline(always)]
    pub fn importance_from_points(&self, c: usize, p: &Vec3x16, n: &Vec3x16, has_n: Mask16) -> F32x16 {
        let one = |v: &Vec4| F32x16::splat(v[c]);
        let three = |v: &[Vec4; 3]| [one(&v[0]), one(&v[1]), one(&v[2])];
        let cluster = ClusterLanes {
            min: three(&self.min),
            max: three(&self.max),
            w: three(&self.w),
            phi: one(&self.phi),
            radius: one(&self.radius),
            cos_theta_o: one(&self.cos_theta_o),
            sin_theta_o: one(&self.sin_theta_o),
            cos_theta_e: one(&self.cos_theta_e),
            two_sided: one(&self.two_sided),
        };
        importance_lanes::importance(&cluster, [p.x, p.y, p.z], [n.x, n.y, n.z], has_n)
    }
}

/// Picks a lane in proportion to `weights` with `u` in [0, 1): (lane, its probability, `u`
/// remapped to [0, 1) within the lane), or None when every weight is 0.
#[inline]
pub(super) fn choose_lane(weights: Vec4, u: f32) -> Option<(usize, f32, f32)> {
    let w = weights.to_array();
    let total = ((w[0] + w[1]) + w[2]) + w[3];
    if !(total > 0.0) {
        return None;
    }
    let target = u * total;
    let (mut lane, mut before) = (0, 0.0);
    let mut acc = 0.0;
    for (k, &wk) in w.iter().enumerate() {
        if wk > 0.0 {
            (lane, before) = (k, acc);
            if target < acc + wk {
                break;
            }
        }
        acc += wk;
    }
    let remapped = ((target - before) / w[lane]).clamp(0.0, super::bvh::ONE_MINUS_EPSILON);
    Some((lane, w[lane] / total, remapped))
}

/// The probability `choose_lane` gives `lane`.
#[inline]
pub(super) fn lane_probability(weights: Vec4, lane: usize) -> f32 {
    let w = weights.to_array();
    let total = ((w[0] + w[1]) + w[2]) + w[3];
    if total > 0.0 { w[lane] / total } else { 0.0 }
}

/// The wide form of a binary tree, and where each binary node sits in it.
#[derive(Clone, Debug, Default)]
pub(super) struct WideTree {
    pub nodes: Vec<WideNode>,
    /// Per binary node: `4 * wide node + lane` of its slot, or [`NONE`] (the root, and interior
    /// nodes collapsed into their parent's wide node).
    pub slot_of: Vec<u32>,
}

impl WideTree {
    /// Collapses the binary tree `binary` (root first, children adjacent, interior root).
    pub fn build(binary: &[Node]) -> Self {
        let mut tree = Self { nodes: Vec::with_capacity(binary.len() / 3 + 1), slot_of: vec![NONE; binary.len()] };
        if binary.first().is_some_and(|root| root.light().is_none()) {
            tree.collapse(binary, 0);
        }
        tree
    }

    /// Appends the wide node of binary interior node `b` (and everything below it); returns its index.
    fn collapse(&mut self, binary: &[Node], b: usize) -> u32 {
        let me = self.nodes.len();
        self.nodes.push(WideNode::empty(b as u32));
        let c = binary[b].index as usize;
        let (mut slots, mut count) = ([0usize; 4], 0);
        for child in [c, c + 1] {
            match binary[child].light() {
                Some(_) => (slots[count], count) = (child, count + 1),
                None => {
                    let g = binary[child].index as usize;
                    (slots[count], slots[count + 1], count) = (g, g + 1, count + 2);
                }
            }
        }
        for (lane, &s) in slots[..count].iter().enumerate() {
            self.slot_of[s] = (4 * me + lane) as u32;
            self.nodes[me].set_lane(lane, &binary[s].query);
            match binary[s].light() {
                Some(id) => (self.nodes[me].child[lane], self.nodes[me].kind[lane]) = (id.row, Some(id.kind)),
                None => {
                    let below = self.collapse(binary, s);
                    self.nodes[me].child[lane] = below;
                }
            }
        }
        me as u32
    }

    /// Writes a binary node's new bounds into its `slot` (from `slot_of`), if it has one.
    #[inline]
    pub fn set_slot(&mut self, slot: u32, q: &ClusterQuery) {
        if slot != NONE {
            self.nodes[slot as usize / 4].set_lane(slot as usize % 4, q);
        }
    }

    /// Starts loading the cache lines `set_slot(slot, ..)` writes.
    #[inline]
    pub fn prefetch_slot(&self, slot: u32) {
        if slot != NONE {
            crate::prefetch::prefetch(&self.nodes, slot as usize / 4);
        }
    }

    /// The slot above wide node `w`: (parent wide node, lane), or None for the root.
    #[inline]
    pub fn parent_slot(&self, w: usize) -> Option<(usize, usize)> {
        let slot = self.slot_of[self.nodes[w].origin as usize];
        (slot != NONE).then_some((slot as usize / 4, slot as usize % 4))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::LightBounds;

    #[test]
    fn lanes_match_the_scalar_importance() {
        let clusters = [
            LightBounds {
                min: Vec3::new(-1.0, 2.0, 0.0),
                max: Vec3::new(3.0, 4.0, 1.0),
                phi: 5.0,
                w: Vec3::Z,
                cos_theta_o: -1.0,
                cos_theta_e: 0.0,
                two_sided: false,
            },
            LightBounds {
                min: Vec3::ONE,
                max: Vec3::ONE,
                phi: 2.0,
                w: Vec3::NEG_Y,
                cos_theta_o: 0.9,
                cos_theta_e: 0.95,
                two_sided: false,
            },
            LightBounds {
                min: Vec3::new(0.0, 3.0, 0.0),
                max: Vec3::new(2.0, 3.0, 2.0),
                phi: 1.0,
                w: Vec3::NEG_Y,
                cos_theta_o: 1.0,
                cos_theta_e: 0.0,
                two_sided: true,
            },
            EMPTY_BOUNDS,
        ];
        let mut node = WideNode::empty(0);
        for (lane, b) in clusters.iter().enumerate() {
            node.set_lane(lane, &ClusterQuery::from(b));
        }
        for (p, n) in
            [(Vec3::ZERO, Vec3::Y), (Vec3::new(1.0, 0.5, 1.0), Vec3::ZERO), (Vec3::new(5.0, 6.0, -2.0), Vec3::X)]
        {
            let wide = node.importance(p, n).to_array();
            for (lane, b) in clusters.iter().enumerate() {
                let scalar = ClusterQuery::from(b).importance(p, n);
                assert!(
                    (wide[lane] - scalar).abs() <= 1e-5 * scalar.abs().max(1e-6),
                    "lane {lane} at {p}: {} vs {scalar}",
                    wide[lane]
                );
            }
        }
    }

    #[test]
    fn lane_choice_follows_the_weights() {
        let w = Vec4::new(1.0, 0.0, 3.0, 0.0);
        assert_eq!(choose_lane(w, 0.1).map(|c| c.0), Some(0));
        assert_eq!(choose_lane(w, 0.3).map(|c| (c.0, c.1)), Some((2, 0.75)));
        assert_eq!(choose_lane(w, 0.999_999).map(|c| c.0), Some(2));
        assert_eq!(choose_lane(Vec4::ZERO, 0.5), None);
        assert_eq!(lane_probability(w, 1), 0.0);
    }
}
