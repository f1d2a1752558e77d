//! Pinhole cameras: the glTF perspective camera (looking along its local -Z, +Y up) and a framing
//! camera for scenes that have none.

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};

use crate::geometry::Transform;
use crate::geometry::ray::Ray;
use crate::lanes::{F32x16, LANES, U32x16, Vec3x16};

/// A perspective camera at its entity's `Transform`, looking along local -Z.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Vertical field of view, radians. Defaults to 45 degrees.
    pub yfov: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Self { yfov: 45f32.to_radians() }
    }
}

/// A camera fixed for one image: generates primary rays per pixel.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    origin: Vec3,
    /// Direction (unnormalised) through the image's top-left corner, and its change per pixel
    /// to the right and per pixel down, so that a ray costs no division.
    corner: Vec3,
    per_x: Vec3,
    per_y: Vec3,
    width: u32,
    height: u32,
}

impl PinholeCamera {
    /// The camera at `transform` rendering a `width` x `height` image.
    pub fn new(camera: &Camera, transform: &Transform, width: u32, height: u32) -> Self {
        let r = transform.aim();
        let (width, height) = (width.max(1), height.max(1));
        let (right, up, forward) =
            ((r * Vec3::X).normalize(), (r * Vec3::Y).normalize(), (r * Vec3::NEG_Z).normalize());
        let tan_half_y = (0.5 * camera.yfov.clamp(1e-4, 3.1)).tan();
        let tan_half_x = tan_half_y * width as f32 / height as f32;
        Self {
            origin: transform.translation,
            corner: forward - right * tan_half_x + up * tan_half_y,
            per_x: right * (2.0 * tan_half_x / width as f32),
            per_y: up * (-2.0 * tan_half_y / height as f32),
            width,
            height,
        }
    }

    /// A camera that frames the sphere (`center`, `radius`) from a direction above and in front.
    /// The sphere fits the narrower of the two fields of view (the horizontal one in a portrait image).
    pub fn framing(center: Vec3, radius: f32, width: u32, height: u32) -> (Camera, Transform) {
        let camera = Camera::default();
        let half_y = 0.5 * camera.yfov;
        let half_x = (half_y.tan() * width.max(1) as f32 / height.max(1) as f32).atan();
        let dist = radius.max(1e-3) / half_y.min(half_x).sin() * 1.1;
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        let transform = Transform::from_translation(center + dir * dist).looking_to(-dir, Vec3::Y);
        (camera, transform)
    }

    /// The ray through image position `pixel + offset` (pixel (0, 0) at the top left; `offset`
    /// in [0, 1)^2 within the pixel).
    pub fn ray(&self, x: u32, y: u32, offset: Vec2) -> Ray {
        let dir = self.corner + self.per_x * (x as f32 + offset.x) + self.per_y * (y as f32 + offset.y);
        Ray::new(self.origin, dir.normalize())
    }

    /// The directions of [`Self::ray`] for `LANES` samples at once, bit for bit: lane `l` is
    /// pixel (`x[l]`, `y[l]`) at offset (`u[l]`, `v[l]`).
    #[inline(always)]
    pub fn dirs_lanes(&self, [x, y]: [&[u32; LANES]; 2], u: &F32x16, v: &F32x16) -> Vec3x16 {
        let (fx, fy) = (U32x16(*x).to_f32() + *u, U32x16(*y).to_f32() + *v);
        // Vec3 arithmetic and `normalize` (times 1 / sqrt(dot)), in the same order.
        let w = Vec3x16::splat(self.corner) + Vec3x16::splat(self.per_x) * fx + Vec3x16::splat(self.per_y) * fy;
        w * (1.0 / w.length())
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

/// A camera at a point that sees every direction: pixel (x, y) of a `width` x `height` image looks
/// along `scene::image::lat_long_direction` of the pixel's (u, v), so its render is a lat-long
/// radiance map that an `ImageInfiniteLight` can use directly (pbrt's `EnvironmentCamera`).
#[derive(Component, Clone, Copy, Debug, PartialEq, Default)]
pub struct EnvironmentCamera;

/// How primary rays leave the camera.
#[derive(Clone, Copy, Debug)]
pub enum CameraModel {
    /// A perspective camera, fixed for one image.
    Pinhole(PinholeCamera),
    /// An environment camera at `origin` rendering a `width` x `height` lat-long map.
    LatLong {
        /// Where every ray starts, world space (metres).
        origin: Vec3,
        /// Map width in pixels (the full turn of longitude).
        width: u32,
        /// Map height in pixels (pole to pole).
        height: u32,
    },
}

impl CameraModel {
    /// The directions of [`Self::ray`] for `LANES` samples of pixels (`x`, `y`) at offsets
    /// (`u`, `v`), as lane columns. Every ray starts at [`Self::origin`].
    #[inline(always)]
    pub fn dirs_lanes(&self, xy: [&[u32; LANES]; 2], u: &F32x16, v: &F32x16) -> Vec3x16 {
        match self {
            Self::Pinhole(c) => c.dirs_lanes(xy, u, v),
            Self::LatLong { .. } => {
                let mut d = Vec3x16::ZERO;
                for l in 0..LANES {
                    d.set_lane(l, self.ray(xy[0][l], xy[1][l], Vec2::new(u[l], v[l])).dir);
                }
                d
            }
        }
    }

    /// Where every ray starts.
    pub fn origin(&self) -> Vec3 {
        match *self {
            Self::Pinhole(c) => c.origin,
            Self::LatLong { origin, .. } => origin,
        }
    }

    /// The ray through pixel (x, y) at `offset` within it.
    pub fn ray(&self, x: u32, y: u32, offset: Vec2) -> Ray {
        match *self {
            Self::Pinhole(c) => c.ray(x, y, offset),
            Self::LatLong { origin, width, height } => {
                let uv = Vec2::new((x as f32 + offset.x) / width as f32, (y as f32 + offset.y) / height as f32);
                Ray::new(origin, crate::scene::image::lat_long_direction(uv))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The hard case is a portrait image, whose horizontal field of view is the narrower: the
    /// framed sphere fits between the image's left and right edges as between its top and bottom.
    #[test]
    fn the_framing_camera_fits_the_sphere_in_either_orientation() {
        let center = Vec3::new(1.0, -2.0, 0.5);
        for (w, h) in [(256, 256), (512, 128), (64, 512)] {
            let (camera, t) = PinholeCamera::framing(center, 2.0, w, h);
            let pinhole = PinholeCamera::new(&camera, &t, w, h);
            let to_center = center - t.translation;
            let needed = (2.0 / to_center.length()).asin();
            // Rays through the middles of the four edges.
            for (x, y, offset) in
                [(0, h / 2, Vec2::ZERO), (w - 1, h / 2, Vec2::X), (w / 2, 0, Vec2::ZERO), (w / 2, h - 1, Vec2::Y)]
            {
                let edge = pinhole.ray(x, y, offset).dir.angle_between(to_center);
                assert!(edge > needed, "{w}x{h}, edge at ({x}, {y}): {edge} rad from the centre, the sphere {needed}");
            }
        }
    }

    #[test]
    fn lane_rays_match_single_rays() {
        let t = Transform::from_translation(Vec3::new(0.3, 3.0, 4.0)).looking_to(Vec3::new(0.1, -3.0, -4.0), Vec3::Y);
        let (w, h) = (37, 23);
        let pinhole = CameraModel::Pinhole(PinholeCamera::new(&Camera { yfov: 1.1 }, &t, w, h));
        let lat_long = CameraModel::LatLong { origin: Vec3::ONE, width: w, height: h };
        let mut rng = SplitMix64::new(5);
        for camera in [pinhole, lat_long] {
            for _ in 0..20 {
                let x: [u32; LANES] = std::array::from_fn(|_| (rng.next_u64() % w as u64) as u32);
                let y: [u32; LANES] = std::array::from_fn(|_| (rng.next_u64() % h as u64) as u32);
                let (u, v) = (F32x16(std::array::from_fn(|_| rng.f32())), F32x16(std::array::from_fn(|_| rng.f32())));
                let dirs = camera.dirs_lanes([&x, &y], &u, &v);
                for l in 0..LANES {
                    let one = camera.ray(x[l], y[l], Vec2::new(u[l], v[l]));
                    assert_eq!(camera.origin(), one.origin);
                    let dir = dirs.lane(l);
                    assert_eq!(dir.to_array().map(f32::to_bits), one.dir.to_array().map(f32::to_bits), "{camera:?}");
                }
            }
        }
    }
}
