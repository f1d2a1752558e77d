//! [`BvhSampler::sample`] for [`LANES`] shading points at once: the lanes that stand at the same
//! wide node weigh its four clusters together, one cluster per pass over all points
//! (`WideNode::importance_from_points`), so a batch's points share each node's loads and the
//! square roots and divisions of the importance run 16 wide. Lanes that end up alone at a node
//! (deep in a large tree, where points part ways) take the 4-wide form instead. Both give the
//! same bits, so every lane's choice and pmf are [`BvhSampler::sample`]'s.

use glam::Vec4;

use super::bvh::{BvhSampler, ONE_MINUS_EPSILON};
use super::wide::choose_lane;
use crate::lanes::{F32x16, LANES, Vec3x16};
use crate::light::{LightId, LightKind};

/// Fewest lanes at one node for which the 16-wide pass pays over 4-wide ones per lane.
const SHARED_PASS_LANES: u32 = 4;

/// The lights chosen for a block of points: per lane the light and its probability, valid in
/// the lanes of `chosen`.
#[derive(Clone, Copy, Debug)]
pub struct LaneChoices {
    /// The light chosen in each lane.
    pub light: [LightId; LANES],
    /// Probability with which each lane's light was chosen.
    pub pmf: [f32; LANES],
    /// Bit mask of the lanes that chose a light (bit l for lane l).
    pub chosen: u32,
}

impl BvhSampler {
    /// [`BvhSampler::sample`] of the lanes of `active`, at points `p` with shading normals `n` (lane
    /// columns; zero normals for none) and numbers `u`. Lanes outside `active` choose nothing.
    /// Run it inside `lanes::widest`.
    #[inline(always)]
    pub fn sample_lanes(&self, p: &Vec3x16, n: &Vec3x16, u: &F32x16, active: u32) -> LaneChoices {
        let none = LightId { kind: LightKind::Point, row: 0 };
        let mut out = LaneChoices { light: [none; LANES], pmf: [0.0; LANES], chosen: 0 };
        let (point, normal) = (|l: usize| p.lane(l), |l: usize| n.lane(l));
        let u = &u.0;
        let p_inf = self.infinite_probability();
        let (mut remapped, mut pmf, mut at) = ([0f32; LANES], [0f32; LANES], [0u32; LANES]);
        // Lanes still walking the tree.
        let mut walking = 0u32;
        let mut lanes = active;
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if u[l] < p_inf || self.nodes.is_empty() || self.nodes[0].light().is_some() {
                // Lights at infinity and one-light trees: as `sample`, one lane at a time.
                let ctx = crate::light::LightSampleContext { p: point(l), n: normal(l), ns: normal(l) };
                if let Some((id, q)) = self.sample(&ctx, u[l]) {
                    (out.light[l], out.pmf[l], out.chosen) = (id, q, out.chosen | 1 << l);
                }
                continue;
            }
            remapped[l] = ((u[l] - p_inf) / (1.0 - p_inf)).min(ONE_MINUS_EPSILON);
            pmf[l] = 1.0 - p_inf;
            walking |= 1 << l;
        }
        let zero = F32x16::ZERO;
        let has_n = n.x.ne(zero) | n.y.ne(zero) | n.z.ne(zero);
        while walking != 0 {
            let w = at[walking.trailing_zeros() as usize];
            let mut here = 0u32;
            for l in 0..LANES {
                here |= u32::from(at[l] == w) << l;
            }
            here &= walking;
            let node = &self.wide.nodes[w as usize];
            let mut weights = [Vec4::ZERO; LANES];
            if here.count_ones() >= SHARED_PASS_LANES {
                let mut c4 = [[0f32; LANES]; 4];
                for (c, column) in c4.iter_mut().enumerate() {
                    *column = node.importance_from_points(c, p, n, has_n).0;
                }
                for (l, weight) in weights.iter_mut().enumerate() {
                    *weight = Vec4::new(c4[0][l], c4[1][l], c4[2][l], c4[3][l]);
                }
            } else {
                let mut lanes = here;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    weights[l] = node.importance(point(l), normal(l));
                }
            }
            let mut lanes = here;
            while lanes != 0 {
                let l = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let Some((slot, q, next_u)) = choose_lane(weights[l], remapped[l]) else {
                    walking &= !(1 << l); // no light reaches this point
                    continue;
                };
                (pmf[l], remapped[l]) = (pmf[l] * q, next_u);
                match node.light(slot) {
                    Some(id) => {
                        (out.light[l], out.pmf[l], out.chosen) = (id, pmf[l], out.chosen | 1 << l);
                        walking &= !(1 << l);
                    }
                    None => at[l] = node.child[slot],
                }
            }
        }
        out
    }
}
