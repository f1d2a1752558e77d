//! The Light interface: the shared types every light type uses, and nothing else.
//!
//! Each light type lives in its own file: its component (user-facing, with units), its resolved
//! world-space form, and pure `sample_li` / `pdf_li` / `radiance` / `le` / `phi` / `bounds`
//! functions on that form. A light is `(LightKind, index)` into per-kind tables; one `match` per
//! operation, no trait objects on hot paths.

pub mod area;
mod dispatch;
pub mod distant;
pub mod emitter;
pub mod goniometric;
pub mod infinite;
pub mod point;
pub mod projection;
pub mod spot;
pub mod table;

use glam::Vec3;

use crate::spectrum::{SampledSpectrum, SampledWavelengths};

pub use area::{AreaLight, AreaShape, LightTexture, ResolvedArea, ResolvedMesh};
pub use distant::{DistantLight, ResolvedDistant};
pub use emitter::{Amount, Emitter, LightError, Quantity};
pub use goniometric::{GonioProfile, GoniometricLight, ResolvedGoniometric};
pub use infinite::{
    EnvLookup, EnvMapTables, EnvTableOptions, ImageInfiniteLight, ResolvedImageInfinite, ResolvedSunSky,
    ResolvedUniformInfinite, SunPosition, SunSkyLight, UniformInfiniteLight,
};
pub use point::{PointLight, ResolvedPoint};
pub use projection::{ProjectionLight, ResolvedProjection};
pub use spot::{ResolvedSpot, SpotLight};
pub use table::{LightId, LightTable};

/// Where light is being gathered: a point with its geometric normal and, optionally, its shading
/// normal. `n == Vec3::ZERO` marks a point not on a surface (a medium, or "no normal").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleContext {
    /// Position, world space (m).
    pub p: Vec3,
    /// Geometric normal (unit) or zero.
    pub n: Vec3,
    /// Shading normal (unit) or zero.
    pub ns: Vec3,
}

impl LightSampleContext {
    /// A context at `p` with no surface.
    pub fn at(p: Vec3) -> Self {
        Self { p, n: Vec3::ZERO, ns: Vec3::ZERO }
    }
    /// A context on a surface with the same geometric and shading normal.
    pub fn on_surface(p: Vec3, n: Vec3) -> Self {
        Self { p, n, ns: n }
    }

    /// The unit direction from here to a point light at `light` and the squared distance; None
    /// at the light itself or when the distance is not finite.
    #[inline]
    pub fn toward(&self, light: Vec3) -> Option<(Vec3, f32)> {
        let d = light - self.p;
        let r2 = d.length_squared();
        // One division and three products, not three divisions: lane kernels (`PointColumns`)
        // repeat this, and divisions are their slowest step.
        (r2 > 0.0 && r2.is_finite()).then(|| (d * (1.0 / r2.sqrt()), r2))
    }

    /// [`Self::toward`] computed in f64 (the light-precision knob of the accuracy report).
    pub fn toward_f64(&self, light: Vec3) -> Option<(glam::DVec3, f64)> {
        let d = light.as_dvec3() - self.p.as_dvec3();
        let r2 = d.length_squared();
        (r2 > 0.0 && r2.is_finite()).then(|| (d / r2.sqrt(), r2))
    }
}

/// Which wavelengths a query is answered in: RGB mode (linear sRGB, photometric: channels 0-2)
/// or spectral mode (spectral radiance, W/(m^2 sr nm), at the sampled wavelengths).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorQuery<'a> {
    /// Linear sRGB in channels 0-2, photometric (channel 3 is zero).
    Rgb,
    /// Spectral radiance at these sampled wavelengths, one channel per wavelength.
    Spectral(&'a SampledWavelengths),
}

impl ColorQuery<'_> {
    /// A light-table row's intensity in this mode: its photometric RGB, or its spectrum times
    /// its scale at the sampled wavelengths.
    #[inline]
    pub fn intensity_column(&self, rgb: Vec3, spectrum: &crate::spectrum::Spectrum, scale: f32) -> SampledSpectrum {
        match self {
            ColorQuery::Rgb => SampledSpectrum([rgb.x, rgb.y, rgb.z, 0.0]),
            ColorQuery::Spectral(w) => w.eval(spectrum).scale(scale),
        }
    }
}

/// A sampled direction toward a light, as data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiSample {
    /// Incident radiance along `-wi` in the query's colour mode (see [`ColorQuery`]). For delta
    /// lights this is the radiance-like quantity I / r^2 (or E) that carries an implicit delta.
    pub radiance: SampledSpectrum,
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3,
    /// Solid-angle density of `wi`; 1 for delta lights.
    pub pdf: f32,
    /// The sampled point on the light (far away along `wi` for distant and infinite lights).
    pub p_light: Vec3,
    /// Surface normal at `p_light` (zero for point-like and infinite lights).
    pub n_light: Vec3,
}

/// Declares [`LightKind`] from one list, so that [`LightKind::ALL`] and [`LightKind::COUNT`]
/// cannot fall out of step with the variants.
macro_rules! light_kinds {
    ($($(#[$doc:meta])* $kind:ident),+ $(,)?) => {
        /// The closed set of light kinds, in the order of their blocks in `LightTable::ids`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum LightKind {
            $($(#[$doc])* $kind,)+
        }

        impl LightKind {
            /// Every kind, in declaration order (`ALL[k.index()] == k`).
            pub const ALL: [LightKind; [$(stringify!($kind)),+].len()] = [$(LightKind::$kind),+];
            /// The number of kinds: the length of per-kind arrays.
            pub const COUNT: usize = Self::ALL.len();
        }
    };
}

light_kinds! {
    /// [`PointLight`].
    Point,
    /// [`SpotLight`].
    Spot,
    /// [`AreaLight`] on a mesh or shape.
    Area,
    /// [`ProjectionLight`].
    Projection,
    /// [`GoniometricLight`].
    Goniometric,
    /// [`DistantLight`].
    Distant,
    /// [`UniformInfiniteLight`].
    UniformInfinite,
    /// [`ImageInfiniteLight`].
    ImageInfinite,
    /// [`SunSkyLight`].
    SunSky,
}

/// Properties of a light's emission, as in the chapter's `LightType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LightFlags(u8);

impl LightFlags {
    /// Emits from a single point (point, spot, projection, goniometric).
    pub const DELTA_POSITION: Self = Self(1);
    /// Emits along a single direction (distant without angular size).
    pub const DELTA_DIRECTION: Self = Self(2);
    /// Emits from a surface (area lights).
    pub const AREA: Self = Self(4);
    /// Surrounds the scene at infinity.
    pub const INFINITE: Self = Self(8);

    /// True if every flag of `other` is set.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
    /// True for lights described by a delta distribution (no pdf over directions).
    pub const fn is_delta(self) -> bool {
        self.0 & (Self::DELTA_POSITION.0 | Self::DELTA_DIRECTION.0) != 0
    }
    /// Union of two flag sets.
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }
}

impl LightKind {
    /// Position of this kind in [`Self::ALL`]: the index of its row in per-kind arrays and of its
    /// block in `LightTable::ids` order.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The flags of this kind. A distant light with an angular diameter is not delta: see
    /// [`ResolvedDistant::flags`].
    pub const fn flags(self) -> LightFlags {
        match self {
            Self::Point | Self::Spot | Self::Projection | Self::Goniometric => LightFlags::DELTA_POSITION,
            Self::Distant => LightFlags::DELTA_DIRECTION,
            Self::Area => LightFlags::AREA,
            Self::UniformInfinite | Self::ImageInfinite | Self::SunSky => LightFlags::INFINITE,
        }
    }
}

/// What a light sampler needs to know about a light: where it is, where it shines, how much.
/// Follows pbrt-v4's `LightBounds` (Conty & Kulla 2018).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Bounding box of the emitting positions, world space.
    pub min: Vec3,
    /// Upper corner of the bounding box (see `min`), world space.
    pub max: Vec3,
    /// Total emitted power, W (radiometric).
    pub phi: f32,
    /// Principal emission direction (unit).
    pub w: Vec3,
    /// Cosine of the spread of surface normals (or emission axes) around `w`.
    pub cos_theta_o: f32,
    /// Cosine of the emission spread beyond `cos_theta_o` (pi/2 for Lambertian emitters).
    pub cos_theta_e: f32,
    /// Emits on both sides of its surface.
    pub two_sided: bool,
}

/// The scene's bounding sphere, handed to distant and infinite lights in their preprocess step
/// (they need it to place sample points "at infinity" and to compute their power).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSphere {
    /// Centre, world space, metres.
    pub center: Vec3,
    /// Radius in metres.
    pub radius: f32,
}

impl Default for SceneSphere {
    fn default() -> Self {
        Self { center: Vec3::ZERO, radius: 1.0 }
    }
}
