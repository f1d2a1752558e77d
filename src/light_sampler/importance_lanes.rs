//! The light BVH's importance formula ([`super::importance::ClusterQuery::importance`], the
//! scalar reference) written once over lane types: a wide node's four clusters seen from one
//! point (`glam::Vec4`), or one cluster seen from `LANES` points (`lanes::F32x16`, for batches of
//! shading points in `BvhSampler::sample_lanes`). Both lane types round every operation as the
//! other does (IEEE +, -, *, /, sqrt; `max` / `min` with SSE's operand order), so a point's
//! importances, and so its choices and pmfs, are the same bits whichever form computed them.

use super::importance::{MAX_IMPORTANCE, MIN_DISTANCE_SQUARED};
use crate::lanes::Real;

/// Cluster bounds as lanes (see `WideNode`): box corners, emission axis, power, bounding-sphere
/// radius, cone cosines and sine, and 1 for two-sided clusters.
#[derive(Clone, Copy, Debug)]
pub(super) struct ClusterLanes<V> {
    pub min: [V; 3],
    pub max: [V; 3],
    pub w: [V; 3],
    pub phi: V,
    pub radius: V,
    pub cos_theta_o: V,
    pub sin_theta_o: V,
    pub cos_theta_e: V,
    pub two_sided: V,
}

/// The importance of each lane's cluster at its point `p` with normal `n` (`has_n`: lanes whose
/// normal is not zero): `ClusterQuery::importance` lane by lane (see there for the model and its
/// sources).
#[inline(always)]
pub(super) fn importance<V: Real>(c: &ClusterLanes<V>, p: [V; 3], n: [V; 3], has_n: V::Mask) -> V {
    let s = V::splat;
    let (zero, one) = (s(0.0), s(1.0));
    let [px, py, pz] = p;
    let [min_x, min_y, min_z] = c.min;
    let [max_x, max_y, max_z] = c.max;
    let (tx, ty, tz) = (px - s(0.5) * (min_x + max_x), py - s(0.5) * (min_y + max_y), pz - s(0.5) * (min_z + max_z));
    let dist2 = tx * tx + ty * ty + tz * tz;
    let (gx, gy, gz) = (
        (min_x - px).max(px - max_x).max(zero),
        (min_y - py).max(py - max_y).max(zero),
        (min_z - pz).max(pz - max_z).max(zero),
    );
    let gap = (gx * gx + gy * gy + gz * gz).sqrt();
    let radius = c.radius;
    let dist = dist2.sqrt();
    let d2 = (dist * gap).max(radius * radius / s(64.0)).max(s(MIN_DISTANCE_SQUARED));
    let inv_dist = V::select(dist2.gt(zero), one / dist, zero);
    let (wx, wy, wz) = (tx * inv_dist, ty * inv_dist, tz * inv_dist);

    let inside = dist2.le(radius * radius);
    let sin_b = V::select(inside, zero, radius * inv_dist);
    let cos_b = V::select(inside, s(-1.0), (one - sin_b * sin_b).max(zero).sqrt());

    // Clusters that emit every way (any point light inside) skip the cone terms: most interior
    // nodes, since points and spots mix.
    let (cos_o, cos_e) = (c.cos_theta_o, c.cos_theta_e);
    let everywhere = cos_o.le(s(-1.0));
    let cos_p = if V::all(everywhere) {
        one
    } else {
        let [ax, ay, az] = c.w;
        let cos_w0 = ax * wx + ay * wy + az * wz;
        let cos_w = V::select(c.two_sided.gt(zero), cos_w0.abs(), cos_w0);
        let sin_w = (one - cos_w * cos_w).max(zero).sqrt();
        let sin_o = c.sin_theta_o;
        let within_o = cos_w.gt(cos_o);
        let cos_x = V::select(within_o, one, cos_w * cos_o + sin_w * sin_o);
        let sin_x = V::select(within_o, zero, sin_w * cos_o - cos_w * sin_o);
        let cos_p = V::select(cos_x.gt(cos_b), one, cos_x * cos_b + sin_x * sin_b);
        V::select(everywhere, one, cos_p)
    };
    let dark = cos_p.lt(cos_e) | c.phi.le(zero);
    let lambertian = cos_e.le(zero) | cos_p.ge(one);
    let emission = if V::all(lambertian) {
        cos_p
    } else {
        let t = ((cos_p - cos_e) / (one - cos_e).max(s(1e-12))).max(zero).min(one);
        V::select(lambertian, cos_p, t * t * (s(3.0) - s(2.0) * t))
    };
    let mut value = c.phi * emission / d2;

    if V::any(has_n) {
        let [nx, ny, nz] = n;
        let cos_i = (wx * nx + wy * ny + wz * nz).abs();
        let sin_i = (one - cos_i * cos_i).max(zero).sqrt();
        let cone_bound = V::select(cos_i.gt(cos_b), one, cos_i * cos_b + sin_i * sin_b);
        let axis = |lo: V, hi: V, pc: V, nc: V| ((lo - pc) * nc, (hi - pc) * nc);
        let (lx, hx) = axis(min_x, max_x, px, nx);
        let (ly, hy) = axis(min_y, max_y, py, ny);
        let (lz, hz) = axis(min_z, max_z, pz, nz);
        let above = lx.max(hx) + ly.max(hy) + lz.max(hz);
        let below = -(lx.min(hx) + ly.min(hy) + lz.min(hz));
        let offset = above.max(below);
        let plane_bound = V::select(offset.ge(gap), one, offset / gap);
        value = V::select(has_n, value * cone_bound.min(plane_bound), value);
    }
    V::select(dark, zero, value.max(zero).min(s(MAX_IMPORTANCE)))
}
