//! glTF node animation (glTF 2.0 spec, section 3.11 "Animations"): channels that drive a node's
//! translation, rotation or scale through keyframes with STEP, LINEAR or CUBICSPLINE
//! interpolation, and the node tree at rest, so that a frame's world transforms can be computed
//! without the document.
//!
//! A bad channel (missing node or accessor, times not increasing, too few values, a node with a
//! `matrix`) is dropped with a warning; the rest of the clip and the scene load as they are.

use ::gltf::json::animation::{Interpolation as JsonInterpolation, Property};
use ::gltf::json::validation::Checked;
use glam::{Affine3A, Quat, Vec3, Vec4};

use super::accessor::read_vectors;
use super::{Doc, Warnings};

/// A node's own transform: a matrix (which glTF forbids animating) or translation, rotation
/// and scale, applied as T * R * S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalTransform {
    /// The node's `matrix`; channels that target such a node are dropped.
    Matrix(Affine3A),
    /// The node's `translation`, `rotation` and `scale`, which channels may drive.
    Trs {
        /// Translation in metres, parent space.
        translation: Vec3,
        /// Rotation (unit quaternion).
        rotation: Quat,
        /// Per-axis scale.
        scale: Vec3,
    },
}

impl LocalTransform {
    /// The node-to-parent matrix (T * R * S for TRS).
    pub fn to_affine(self) -> Affine3A {
        match self {
            Self::Matrix(m) => m,
            Self::Trs { translation, rotation, scale } => {
                Affine3A::from_scale_rotation_translation(scale, rotation, translation)
            }
        }
    }
}

/// What a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The node's translation (xyz).
    Translation,
    /// The node's rotation (quaternion xyzw, renormalised when sampled).
    Rotation,
    /// The node's scale (xyz).
    Scale,
}

/// How values between keyframes are found (glTF 2.0 spec, Appendix C "Interpolation").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Holds each keyframe's value until the next keyframe.
    Step,
    /// Linear between keyframes (spherical linear for rotations).
    Linear,
    /// Hermite spline; each keyframe stores an in-tangent, a value and an out-tangent.
    CubicSpline,
}

/// Keyframes of one channel. Vectors are stored as `Vec4` (translation and scale in xyz,
/// rotation as the quaternion xyzw).
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes {
    /// Strictly increasing, finite, seconds.
    times: Vec<f32>,
    /// One value per time, or for CUBICSPLINE three (in-tangent, value, out-tangent).
    values: Vec<Vec4>,
    interpolation: Interpolation,
}

impl Keyframes {
    /// Keyframes after the checks glTF asks for; the error says what is wrong.
    pub fn new(times: Vec<f32>, values: Vec<Vec4>, interpolation: Interpolation) -> Result<Self, String> {
        if times.is_empty() {
            return Err("no keyframes".into());
        }
        if let Some(t) = times.iter().find(|t| !t.is_finite()) {
            return Err(format!("keyframe time {t} is not finite"));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!("keyframe times not strictly increasing at {k} ({} then {})", times[k], times[k + 1]));
        }
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if values.len() != per_key * times.len() {
            return Err(format!(
                "{} output values for {} keyframes ({per_key} each needed)",
                values.len(),
                times.len()
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err("NaN or infinite output values".into());
        }
        Ok(Self { times, values, interpolation })
    }

    /// Rotation keys must be quaternions of non-zero length (the spec asks for unit ones; any
    /// other length is normalised, but a zero one has no rotation and would pose NaN).
    fn check_rotations(&self) -> Result<(), String> {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let keys = (0..self.times.len()).map(|k| if cubic { self.values[3 * k + 1] } else { self.values[k] });
        match keys.enumerate().find(|(_, q)| q.length() < 1e-6) {
            Some((k, q)) => Err(format!("rotation keyframe {k} is {q}, a quaternion of zero length")),
            None => Ok(()),
        }
    }

    /// The last keyframe's time.
    pub fn end(&self) -> f32 {
        *self.times.last().expect("at least one keyframe")
    }

    /// The value at time `t`: the first value before the first keyframe, the last after the last.
    pub fn sample(&self, t: f32, target: Target) -> Vec4 {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| if cubic { self.values[3 * k + 1] } else { self.values[k] };
        let n = self.times.len();
        // Keyframe k is the last with times[k] <= t.
        let next = self.times.partition_point(|&tk| tk <= t);
        if next == 0 {
            return value(0);
        }
        if next == n {
            return value(n - 1);
        }
        let k = next - 1;
        let (t0, t1) = (self.times[k], self.times[next]);
        let span = t1 - t0;
        let s = ((t - t0) / span).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if target == Target::Rotation => {
                let (a, b) = (Quat::from_vec4(value(k)), Quat::from_vec4(value(next)));
                // glam's slerp takes the shorter of the arcs to b and -b, as spec Appendix C asks.
                Vec4::from(a.normalize().slerp(b.normalize(), s))
            }
            Interpolation::Linear => value(k).lerp(value(next), s),
            Interpolation::CubicSpline => {
                // p(s) = (2s^3 - 3s^2 + 1) v_k + (s^3 - 2s^2 + s) span b_k + (-2s^3 + 3s^2) v_k+1
                //        + (s^3 - s^2) span a_k+1 (spec Appendix C, b the out-, a the in-tangent).
                let (s2, s3) = (s * s, s * s * s);
                let out_tangent = self.values[3 * k + 2];
                let in_tangent = self.values[3 * next];
                let p = (2.0 * s3 - 3.0 * s2 + 1.0) * value(k)
                    + (s3 - 2.0 * s2 + s) * span * out_tangent
                    + (-2.0 * s3 + 3.0 * s2) * value(next)
                    + (s3 - s2) * span * in_tangent;
                if target == Target::Rotation { p.normalize_or_zero() } else { p }
            }
        }
    }
}

/// One channel: a node's property driven by keyframes.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Index of the driven node in the file's `nodes`.
    pub node: usize,
    /// Which of its properties.
    pub target: Target,
    /// The property's values over time.
    pub keys: Keyframes,
}

/// An animation of the file: channels played together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationClip {
    /// The animation's `name`, if the file gives one.
    pub name: Option<String>,
    /// The channels kept (bad ones were dropped with a warning).
    pub channels: Vec<Channel>,
}

impl AnimationClip {
    /// The time of the clip's last keyframe, s (0 without channels).
    pub fn duration(&self) -> f32 {
        self.channels.iter().map(|c| c.keys.end()).fold(0.0, f32::max)
    }
}

/// The chosen scene's node tree at rest and the file's animations.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneAnimations {
    /// Per glTF node, its rest transform (the identity for nodes outside the scene).
    pub rest: Vec<LocalTransform>,
    /// Per glTF node, its parent in the chosen scene.
    pub parent: Vec<Option<usize>>,
    /// The scene's nodes, each after its parent.
    pub order: Vec<usize>,
    /// The file's animations, in file order (a clip's index is its glTF animation index).
    pub clips: Vec<AnimationClip>,
}

impl SceneAnimations {
    /// Index of the clip named `name`, or numbered `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.clips
            .iter()
            .position(|c| c.name.as_deref() == Some(name))
            .or_else(|| name.parse::<usize>().ok().filter(|&i| i < self.clips.len()))
    }

    /// Per glTF node, whether clip `clip` moves it (it or an ancestor has a channel).
    pub fn moved_by(&self, clip: usize) -> Vec<bool> {
        let mut moved = vec![false; self.rest.len()];
        for c in self.clips.get(clip).map_or(&[][..], |c| &c.channels) {
            moved[c.node] = true;
        }
        for &n in &self.order {
            if let Some(p) = self.parent[n] {
                moved[n] |= moved[p];
            }
        }
        moved
    }

    /// Every node's local-to-world transform at time `t` (s) of clip `clip`; the rest pose for a
    /// clip that does not exist.
    pub fn pose(&self, clip: usize, t: f32) -> Vec<Affine3A> {
        let mut local = self.rest.clone();
        for c in self.clips.get(clip).map_or(&[][..], |c| &c.channels) {
            let LocalTransform::Trs { translation, rotation, scale } = &mut local[c.node] else { continue };
            let v = c.keys.sample(t, c.target);
            match c.target {
                Target::Translation => *translation = v.truncate(),
                // A cubic spline between keys of opposite sign can pass through zero: that
                // instant keeps the rest rotation rather than a NaN one.
                Target::Rotation => {
                    if let Some(q) = v.try_normalize() {
                        *rotation = Quat::from_vec4(q);
                    }
                }
                Target::Scale => *scale = v.truncate(),
            }
        }
        let mut world = vec![Affine3A::IDENTITY; local.len()];
        for &n in &self.order {
            let parent = self.parent[n].map_or(Affine3A::IDENTITY, |p| world[p]);
            world[n] = parent * local[n].to_affine();
        }
        world
    }
}

/// Reads every animation of the file; `rest` tells which nodes have a matrix.
pub(super) fn read_clips(doc: &Doc, rest: &[LocalTransform], warnings: &mut Warnings) -> Vec<AnimationClip> {
    let mut clips = Vec::new();
    for (a, animation) in doc.root.animations.iter().enumerate() {
        let mut clip = AnimationClip { name: animation.name.clone(), channels: Vec::new() };
        for (c, channel) in animation.channels.iter().enumerate() {
            let pointer = format!("/animations/{a}/channels/{c}");
            match read_channel(doc, animation, channel, rest) {
                Ok(Some(ch)) => clip.channels.push(ch),
                Ok(None) => warnings.push(&pointer, "morph target weights are not animated; channel ignored"),
                Err(msg) => warnings.push(&pointer, format!("{msg}; channel dropped")),
            }
        }
        clips.push(clip);
    }
    clips
}

fn read_channel(
    doc: &Doc,
    animation: &::gltf::json::Animation,
    channel: &::gltf::json::animation::Channel,
    rest: &[LocalTransform],
) -> Result<Option<Channel>, String> {
    let target = match channel.target.path {
        Checked::Valid(Property::Translation) => Target::Translation,
        Checked::Valid(Property::Rotation) => Target::Rotation,
        Checked::Valid(Property::Scale) => Target::Scale,
        Checked::Valid(Property::MorphTargetWeights) => return Ok(None),
        Checked::Invalid => return Err("invalid target path".into()),
    };
    let node = channel.target.node.value();
    match rest.get(node) {
        None => return Err(format!("node {node} does not exist")),
        Some(LocalTransform::Matrix(_)) => {
            return Err(format!("node {node} has a matrix, which glTF forbids animating"));
        }
        Some(_) => {}
    }
    let s = channel.sampler.value();
    let sampler = animation.samplers.get(s).ok_or_else(|| format!("sampler {s} does not exist"))?;
    let interpolation = match sampler.interpolation {
        Checked::Valid(JsonInterpolation::Step) => Interpolation::Step,
        Checked::Valid(JsonInterpolation::Linear) => Interpolation::Linear,
        Checked::Valid(JsonInterpolation::CubicSpline) => Interpolation::CubicSpline,
        Checked::Invalid => return Err(format!("sampler {s}: invalid interpolation")),
    };
    let error = |e: super::GltfError| format!("sampler {s}: {e}");
    let times = read_vectors::<1>(doc, sampler.input.value(), "animation input").map_err(error)?;
    let times = times.into_iter().map(|[t]| t).collect();
    let values: Vec<Vec4> = if target == Target::Rotation {
        let v = read_vectors::<4>(doc, sampler.output.value(), "rotation output").map_err(error)?;
        v.into_iter().map(Vec4::from_array).collect()
    } else {
        let v = read_vectors::<3>(doc, sampler.output.value(), "animation output").map_err(error)?;
        v.into_iter().map(|v| Vec3::from_array(v).extend(0.0)).collect()
    };
    let keys = Keyframes::new(times, values, interpolation).map_err(|e| format!("sampler {s}: {e}"))?;
    if target == Target::Rotation {
        keys.check_rotations().map_err(|e| format!("sampler {s}: {e}"))?;
    }
    Ok(Some(Channel { node, target, keys }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(times: &[f32], values: &[[f32; 3]], interpolation: Interpolation) -> Keyframes {
        let values = values.iter().map(|&v| Vec3::from_array(v).extend(0.0)).collect();
        Keyframes::new(times.to_vec(), values, interpolation).unwrap()
    }

    #[test]
    fn step_and_linear_hold_the_ends_and_interpolate_between() {
        let step = keys(&[1.0, 2.0, 4.0], &[[0.0; 3], [1.0; 3], [5.0; 3]], Interpolation::Step);
        let linear = keys(&[1.0, 2.0, 4.0], &[[0.0; 3], [1.0; 3], [5.0; 3]], Interpolation::Linear);
        for (t, s, l) in [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.5, 0.0, 0.5), (2.0, 1.0, 1.0), (3.0, 1.0, 3.0)] {
            assert_eq!(step.sample(t, Target::Translation).x, s, "step at {t}");
            assert!((linear.sample(t, Target::Translation).x - l).abs() < 1e-6, "linear at {t}");
        }
        assert_eq!(step.sample(9.0, Target::Scale).x, 5.0);
        assert_eq!(linear.sample(4.0, Target::Scale).x, 5.0);
    }

    /// The hard case: a cubic spline from q to -q with zero tangents is the zero quaternion half way;
    /// the pose keeps the rest rotation there (finite), and follows the keys elsewhere.
    #[test]
    fn a_rotation_spline_through_zero_poses_the_rest_rotation() {
        let q = Quat::from_rotation_y(0.7);
        let values = [Vec4::ZERO, Vec4::from(q), Vec4::ZERO, Vec4::ZERO, -Vec4::from(q), Vec4::ZERO];
        let keys = Keyframes::new(vec![0.0, 2.0], values.to_vec(), Interpolation::CubicSpline).unwrap();
        assert_eq!(keys.sample(1.0, Target::Rotation), Vec4::ZERO);
        let rest = Quat::from_rotation_x(0.2);
        let scene = SceneAnimations {
            rest: vec![LocalTransform::Trs { translation: Vec3::ZERO, rotation: rest, scale: Vec3::ONE }],
            parent: vec![None],
            order: vec![0],
            clips: vec![AnimationClip {
                name: None,
                channels: vec![Channel { node: 0, target: Target::Rotation, keys }],
            }],
        };
        let half_way = scene.pose(0, 1.0)[0];
        assert!(half_way.abs_diff_eq(Affine3A::from_quat(rest), 1e-6), "{half_way:?}");
        assert!(scene.pose(0, 0.0)[0].abs_diff_eq(Affine3A::from_quat(q), 1e-6));
    }

    /// Hermite basis at s = 1/2 is (1/2, 1/8, 1/2, -1/8): with values 0 and 2 over a span of 2,
    /// out-tangent 3 and in-tangent -1, p = 1 + 2 (3/8 + 1/8) = 2.
    #[test]
    fn cubic_spline_follows_the_hermite_basis_with_tangents_scaled_by_the_span() {
        let values = [[9.0; 3], [0.0; 3], [3.0; 3], [-1.0; 3], [2.0; 3], [9.0; 3]];
        let k = keys(&[1.0, 3.0], &values, Interpolation::CubicSpline);
        assert!((k.sample(2.0, Target::Translation).x - 2.0).abs() < 1e-6);
        // The ends are the values, not the tangents.
        assert_eq!(k.sample(0.0, Target::Translation).x, 0.0);
        assert_eq!(k.sample(5.0, Target::Translation).x, 2.0);
    }

    /// Hard cases: keys whose quaternions have a negative dot product, by sign (r = -q') or by angle
    /// (rotations 5 rad apart): the shorter arc is taken at constant angular speed, so the pose at
    /// s is the rotation by 0.3 + s (shortest signed angle between the keys), up to sign.
    #[test]
    fn linear_rotation_takes_the_shorter_arc_at_constant_speed() {
        use std::f32::consts::TAU;
        for (end, arc) in [(-Quat::from_rotation_y(0.5), 0.2f32), (Quat::from_rotation_y(5.3), 5.0 - TAU)] {
            let q = Quat::from_rotation_y(0.3);
            let k =
                Keyframes::new(vec![0.0, 2.0], vec![Vec4::from(q), Vec4::from(end)], Interpolation::Linear).unwrap();
            for s in [0.0f32, 0.1, 0.25, 0.5, 0.8, 1.0] {
                let got = Quat::from_vec4(k.sample(2.0 * s, Target::Rotation));
                let want = Quat::from_rotation_y(0.3 + s * arc);
                // The same rotation up to sign (angle_between's acos is too coarse near 1 in f32).
                assert!(got.dot(want).abs() > 1.0 - 1e-6, "arc {arc} at s = {s}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn keyframes_that_break_the_spec_are_refused_with_a_reason() {
        let v = |n: usize| vec![Vec4::ZERO; n];
        let refuse = |times: Vec<f32>, values, i| Keyframes::new(times, values, i).unwrap_err();
        assert!(refuse(vec![], v(0), Interpolation::Linear).contains("no keyframes"));
        assert!(refuse(vec![0.0, 0.0], v(2), Interpolation::Linear).contains("strictly increasing"));
        assert!(refuse(vec![0.0, f32::NAN], v(2), Interpolation::Step).contains("not finite"));
        assert!(refuse(vec![0.0, 1.0], v(2), Interpolation::CubicSpline).contains("3 each"));
        let nan = vec![Vec4::NAN; 2];
        assert!(refuse(vec![0.0, 1.0], nan, Interpolation::Linear).contains("NaN"));
    }
}
