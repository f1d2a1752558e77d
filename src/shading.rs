//! The light system's inputs and outputs as resources: the points to shade, the settings, and the
//! direct lighting written back per point, plus the report of which systems ran.

use bevy_ecs::resource::Resource;
use glam::Vec3;

use crate::geometry::GeometryId;
use crate::light::LightId;
use crate::spectrum::{SampledSpectrum, SampledWavelengths};

/// RGB (linear sRGB, photometric) or spectral (sampled wavelengths per point).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ColorMode {
    /// Linear sRGB channels holding photometric quantities (nit, lx). The default.
    #[default]
    Rgb,
    /// Spectral radiometric quantities at each point's sampled wavelengths.
    Spectral,
}

/// How a light is chosen for each sample. Defaults to the light BVH, as in pbrt-v4: it weighs
/// each light by what reaches the point, where power sampling spends samples on bright lights
/// the point cannot see (the default scene's sky, behind the room's walls).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSamplerKind {
    /// Every light equally likely.
    Uniform,
    /// Proportional to emitted power (alias table).
    Power,
    /// Light BVH with orientation-cone importance (Conty & Kulla 2018).
    #[default]
    Bvh,
}

/// Whether each point gets one sampled light or every light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSelection {
    /// One light per point, chosen by the light sampler (pdf includes its pmf).
    #[default]
    OneSampled,
    /// Every light, each with its own sample (pmf 1).
    All,
    /// Resampled importance sampling (Talbot et al. 2005): `candidates` light samples drawn as
    /// `OneSampled` draws one, one kept in proportion to its unshadowed contribution, one shadow
    /// ray. The entry's pdf is then the estimator's 1/W, which no BSDF sample can know: a
    /// renderer weighs such entries 1 and gives BSDF samples that find emitters weight 0.
    Resampled {
        /// Light samples drawn per entry (M); 0 counts as 1.
        candidates: u32,
    },
    /// Reservoir reuse after RIS (Bitterli et al. 2020, "Spatiotemporal reservoir resampling",
    /// ReSTIR): each entry's RIS reservoir is combined with last run's reservoir at the same
    /// surface point (`ShadingBatch::previous`) and then with neighbours' in the batch's image
    /// (`ShadingBatch::layout`). Entries are weighed as `Resampled` ones (pdf = 1/W).
    Restir(Restir),
}

impl LightSelection {
    /// Whether entries are resampled (`Resampled`, `Restir`): their pdf is an estimator's 1/W,
    /// not a density a BSDF sample can know, so they take no MIS.
    pub fn is_resampled(&self) -> bool {
        matches!(self, Self::Resampled { .. } | Self::Restir(_))
    }
}

/// The knobs of [`LightSelection::Restir`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Restir {
    /// RIS candidates per entry (M of the initial reservoir).
    pub candidates: u32,
    /// Neighbours combined per entry (k; 0: no spatial reuse). Needs `ShadingBatch::layout`.
    pub spatial: u32,
    /// Radius of the neighbourhood, pixels.
    pub radius: u32,
    /// Combine with the previous run's reservoirs (needs `ShadingBatch::previous`).
    pub temporal: bool,
    /// The previous reservoir's M is capped at `history_cap` x `candidates` (the paper's 20), so
    /// stale history cannot dominate.
    pub history_cap: u32,
    /// How the combined reservoirs are weighed.
    pub weights: ReuseWeights,
}

impl Default for Restir {
    fn default() -> Self {
        Self { candidates: 8, spatial: 4, radius: 16, temporal: true, history_cap: 20, weights: ReuseWeights::Unbiased }
    }
}

/// MIS weights of a reservoir combination.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ReuseWeights {
    /// Balance heuristic over the combined reservoirs' targets and M (the paper's Sec. 4.3
    /// weight p_hat_s(y) / sum_j M_j p_hat_j(y)): unbiased, one target evaluation per source
    /// for the chosen sample.
    #[default]
    Unbiased,
    /// 1 / sum M (the paper's Algorithm 4): no extra target evaluations, biased (darker) where a
    /// neighbour's target is zero for a sample the point's is not.
    Biased,
}

/// The batch's points as an image, for spatial reuse: global slot `first + i` of point `i` is
/// sample `(first + i) % samples_per_pixel` of pixel `(first + i) / samples_per_pixel`, pixels
/// row-major `width` to a row. Neighbours are the same sample of nearby pixels in the batch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageLayout {
    /// Image width, pixels.
    pub width: u32,
    /// Consecutive slots per pixel.
    pub samples_per_pixel: u32,
    /// Global slot of the batch's point 0.
    pub first: u64,
}

/// Floating-point precision of the light math where kelvin has both (point and spot Sample_Li:
/// the vector to the light, its length and 1/r^2); other light types always use f32.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightPrecision {
    /// Single precision, the default.
    #[default]
    F32,
    /// Double precision, the reference of the accuracy report.
    F64,
}

/// What the light system computes and how.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct Settings {
    /// RGB or spectral. Defaults to RGB.
    pub color_mode: ColorMode,
    /// How lights are chosen. Defaults to the light BVH.
    pub light_sampler: LightSamplerKind,
    /// One sampled light per sample, every light, or resampling. Defaults to one sampled light.
    pub selection: LightSelection,
    /// Trace shadow rays (when there is geometry that can occlude).
    pub shadows: bool,
    /// Light samples per point per update (k). Each entry's pdf carries k (see
    /// `DirectLighting::pdf`), so summing a point's entries gives the estimate.
    pub samples_per_point: u32,
    /// Seed of the counter-based random numbers.
    pub seed: u64,
    /// Which random numbers samples draw. Defaults to Sobol. (ReSTIR's light samples are always
    /// independent: see [`Settings::light_pattern`].)
    pub pattern: crate::rng::Pattern,
    /// The caller combines light samples with BSDF samples by MIS, so image lights may sample
    /// their MIS-compensated tables (which never sample texels below the map's mean: light
    /// samples alone would then miss their light). Defaults to false, so that the estimator of
    /// [`DirectLighting::irradiance`] is unbiased; an integrator that weighs BSDF samples by MIS
    /// sets it (kelvin's renderer does). Resampled
    /// selections take no MIS, so under them the tables are never compensated (see
    /// [`Settings::compensates_image_lights`]).
    pub mis: bool,
    /// How shadow rays leave the shading point (and area-light points). Defaults to the
    /// error-bound offset.
    pub shadow_offset: crate::geometry::ShadowOffset,
    /// Precision of point and spot light sampling. Defaults to f32.
    pub light_precision: LightPrecision,
    /// How the light sampler follows changed lights. Defaults to incremental updates.
    pub light_updates: LightUpdates,
}

/// How the light sampler follows lights that moved or changed power.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightUpdates {
    /// Refit the light BVH (rebuilt past a cost ratio): fastest, but the tree, and so the noise
    /// of an image, depends on the frames before it.
    #[default]
    Incremental,
    /// Build the sampler afresh on any change: a frame's image is the same bit for bit whether it
    /// is rendered alone, in a chunk or after any other frames (what a render farm needs).
    Rebuild,
}

impl Settings {
    /// The pattern of the light system's streams: the settings' one, but independent numbers
    /// under ReSTIR, whose temporal reuse combines a pixel's successive samples (a stratified
    /// pattern makes them dependent, and the combination biased).
    pub fn light_pattern(&self) -> crate::rng::Pattern {
        if matches!(self.selection, LightSelection::Restir(_)) {
            crate::rng::Pattern::Independent
        } else {
            self.pattern
        }
    }

    /// Whether image lights sample their MIS-compensated tables (density of max(0, L - mean)):
    /// only where BSDF samples weighted by MIS cover the texels those tables skip.
    pub fn compensates_image_lights(&self) -> bool {
        self.mis && !self.selection.is_resampled()
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            color_mode: ColorMode::Rgb,
            light_sampler: LightSamplerKind::Bvh,
            selection: LightSelection::OneSampled,
            shadows: true,
            samples_per_point: 1,
            seed: 0,
            pattern: crate::rng::Pattern::Sobol,
            mis: false,
            shadow_offset: crate::geometry::ShadowOffset::ErrorBound,
            light_precision: LightPrecision::F32,
            light_updates: LightUpdates::Incremental,
        }
    }
}

/// Points to shade, as columns. All columns have `len()` entries; `wavelengths` is filled in
/// spectral mode only. The caller (a renderer's camera rays or an app's G-buffer) writes it.
#[derive(Resource, Clone, Debug, Default)]
pub struct ShadingBatch {
    /// World positions, m. A non-finite position marks a slot with no point (a camera ray that
    /// hit nothing, a G-buffer's sky): it gets entries, all without light or shadow ray.
    pub position: Vec<Vec3>,
    /// Per-axis error bound of each position (for robust shadow-ray offsets; see
    /// `geometry::ray`). `push` fills a conservative bound for points of unknown origin.
    pub position_error: Vec<Vec3>,
    /// Geometric normals (unit), or zero for points not on a surface.
    pub normal: Vec<Vec3>,
    /// Shading normals (unit); the geometric normal where absent.
    pub shading_normal: Vec<Vec3>,
    /// Pixel (or any stable point id) and sample index, the keys of the random numbers.
    pub pixel: Vec<u32>,
    /// Sample index within the pixel (see `pixel`).
    pub sample: Vec<u32>,
    /// Wavelengths per point, spectral mode only.
    pub wavelengths: Vec<SampledWavelengths>,
    /// Empty, or per point the primitive it lies on (`GeometryId::NONE` where unknown), as a
    /// ray hit tells it. Shadow rays then pass through their own flat primitive (see
    /// `SceneBvh::occluded_from`), which no rounding can make shadow itself.
    pub geometry: Vec<GeometryId>,
    /// For spatial reuse ([`LightSelection::Restir`]): where the points lie in an image.
    pub layout: Option<ImageLayout>,
    /// Empty, or per point its index in the previous run's batch ([`NO_PREVIOUS`] for none), for
    /// temporal reuse: a fixed set of points passes `i`, a renderer its reprojection.
    pub previous: Vec<u32>,
}

/// A point with no previous point (see `ShadingBatch::previous`).
pub const NO_PREVIOUS: u32 = u32::MAX;

impl ShadingBatch {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// True with no points.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
    /// Empties every column, keeping capacity.
    pub fn clear(&mut self) {
        self.position.clear();
        self.position_error.clear();
        self.normal.clear();
        self.shading_normal.clear();
        self.pixel.clear();
        self.sample.clear();
        self.wavelengths.clear();
        self.geometry.clear();
        self.previous.clear();
        self.layout = None;
    }
    /// Sizes every column but `wavelengths` (which it empties) to `n` points, `geometry` included,
    /// keeping whatever values they held (new slots of `geometry` are `GeometryId::NONE`): for a
    /// caller about to write every slot of them.
    pub fn set_len(&mut self, n: usize) {
        self.wavelengths.clear();
        self.geometry.resize(n, GeometryId::NONE);
        if !self.previous.is_empty() {
            self.previous.resize(n, NO_PREVIOUS);
        }
        self.position.resize(n, Vec3::ZERO);
        self.position_error.resize(n, Vec3::ZERO);
        self.normal.resize(n, Vec3::ZERO);
        self.shading_normal.resize(n, Vec3::ZERO);
        self.pixel.resize(n, 0);
        self.sample.resize(n, 0);
    }

    /// Appends a point on a surface whose position error is unknown (an app's G-buffer).
    pub fn push(&mut self, position: Vec3, normal: Vec3, pixel: u32, sample: u32) {
        let error = crate::geometry::SurfacePoint::from_point(position, normal).p_error;
        self.push_with_error(position, error, normal, normal, pixel, sample);
    }

    /// Appends a point with a known position error bound and separate shading normal (a ray hit).
    pub fn push_with_error(
        &mut self,
        position: Vec3,
        error: Vec3,
        normal: Vec3,
        shading: Vec3,
        pixel: u32,
        sample: u32,
    ) {
        self.position.push(position);
        self.position_error.push(error);
        self.normal.push(normal);
        self.shading_normal.push(shading);
        self.pixel.push(pixel);
        self.sample.push(sample);
        if !self.geometry.is_empty() {
            self.geometry.push(GeometryId::NONE);
        }
        if !self.previous.is_empty() {
            self.previous.push(NO_PREVIOUS);
        }
    }

    /// The primitive point `i` lies on, if the batch says.
    #[inline(always)]
    pub fn geometry_of(&self, i: usize) -> GeometryId {
        self.geometry.get(i).copied().unwrap_or(GeometryId::NONE)
    }
}

/// Direct light per point in compressed rows: point `i` owns entries
/// `offsets[i]..offsets[i + 1]` (one per sample in one-light mode, one per light and sample in
/// all-lights mode). An entry's `radiance` is zero when the light sample failed or is occluded.
#[derive(Resource, Clone, Debug, Default)]
pub struct DirectLighting {
    /// Start of each point's entries, plus the end: `len()` of the batch + 1 values.
    pub offsets: Vec<u32>,
    /// Incident radiance Li (visibility applied), in the batch's colour mode.
    pub radiance: Vec<SampledSpectrum>,
    /// Unit direction toward the light.
    pub wi: Vec<Vec3>,
    /// The density of the point's samples of this light together: solid-angle pdf times the
    /// light's selection probability times `Settings::samples_per_point` = k (delta lights: the
    /// pmf times k; under `All` the pmf is 1; resampled entries: k / W). So the sum over a
    /// point's entries of f Li cos / pdf is its estimate (no division by k), and MIS weighs an
    /// entry against a BSDF sample with this pdf as it stands (Veach's n_i p_i).
    pub pdf: Vec<f32>,
    /// Which light.
    pub light: Vec<LightId>,
    /// True for delta lights (no MIS with BSDF sampling).
    pub delta: Vec<bool>,
    /// True where a shadow ray found an occluder.
    pub occluded: Vec<bool>,
}

impl DirectLighting {
    /// Entries of point `i`.
    pub fn entries(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }
    /// The irradiance estimate at point `i` of normal `n`: the sum over its entries of
    /// Li max(0, n . wi) / pdf (visibility applied; each pdf carries the samples per point).
    pub fn irradiance(&self, i: usize, n: Vec3) -> SampledSpectrum {
        self.entries(i).filter(|&e| self.pdf[e] > 0.0).fold(SampledSpectrum::default(), |sum, e| {
            sum.add(self.radiance[e].scale(n.dot(self.wi[e]).max(0.0) / self.pdf[e]))
        })
    }
    /// Number of entries.
    pub fn len(&self) -> usize {
        self.wi.len()
    }
    /// True with no entries.
    pub fn is_empty(&self) -> bool {
        self.wi.is_empty()
    }
    /// Empties every column, keeping capacity.
    pub fn clear(&mut self) {
        self.offsets.clear();
        self.radiance.clear();
        self.wi.clear();
        self.pdf.clear();
        self.light.clear();
        self.delta.clear();
        self.occluded.clear();
    }
}

/// One line of the run report: a system and whether it ran this update, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunEntry {
    /// The system's name.
    pub system: &'static str,
    /// Whether it ran this update.
    pub ran: bool,
    /// Why it ran or was skipped.
    pub why: String,
    /// How many items a decision to run covers and of what (`(16384, "points")`), for systems
    /// that count their work; [`RunSummary`] sums them over updates.
    pub count: Option<(u64, &'static str)>,
}

/// Which systems ran in one update and why each skipped one was skipped, plus that update's
/// warnings (lights rejected for bad parameters, and so on).
///
/// **One update only.** Every update starts by clearing it (`begin_update`), so an app that runs
/// the schedule once per frame reads this frame's decisions and warnings here, after the run. A
/// caller that runs the schedule more than once and wants all of it folds each update into a
/// [`RunSummary`] right after the run: the renderer does so for every update of a render (its
/// batches and the update before them) in `RenderStats::report`, which `kelvin render --report`
/// prints.
#[derive(Resource, Clone, Debug, Default)]
pub struct RunReport {
    /// One decision per system, in the order the systems made them.
    pub entries: Vec<RunEntry>,
    /// This update's warnings.
    pub warnings: Vec<String>,
}

impl RunReport {
    /// Records a decision.
    pub fn record(&mut self, system: &'static str, ran: bool, why: impl Into<String>) {
        self.entries.push(RunEntry { system, ran, why: why.into(), count: None });
    }
    /// Records a decision to run that covers `count` items of `unit` (points, rays).
    pub fn record_count(
        &mut self,
        system: &'static str,
        ran: bool,
        why: impl Into<String>,
        count: u64,
        unit: &'static str,
    ) {
        self.entries.push(RunEntry { system, ran, why: why.into(), count: Some((count, unit)) });
    }
    /// Did `system` run in the last update?
    pub fn ran(&self, system: &str) -> bool {
        self.entries.iter().any(|e| e.system == system && e.ran)
    }
}

impl std::fmt::Display for RunReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for e in &self.entries {
            writeln!(f, "{:<28} {:<8} {}", e.system, if e.ran { "ran" } else { "skipped" }, e.why)?;
        }
        for w in &self.warnings {
            writeln!(f, "warning: {w}")?;
        }
        Ok(())
    }
}

/// Many updates' [`RunReport`]s folded into one (with [`RunSummary::add`] after each update):
/// per system and outcome, how many updates ran or skipped it, the counts summed and the last
/// reason; and every warning of every update, in order. Its size grows with the warnings only.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RunSummary {
    /// Updates folded in.
    pub updates: u32,
    /// One line per system and outcome, systems in the order first seen, ran before skipped.
    pub lines: Vec<SummaryLine>,
    /// Every update's warnings, in order.
    pub warnings: Vec<String>,
}

/// A system's updates with one outcome, in a [`RunSummary`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SummaryLine {
    /// The system's name.
    pub system: &'static str,
    /// The outcome: ran, or skipped.
    pub ran: bool,
    /// Updates with this outcome.
    pub updates: u32,
    /// The sum of their counts and the unit, if their decisions count work.
    pub count: Option<(u64, &'static str)>,
    /// The reason the last of them gave.
    pub last_why: String,
}

impl RunSummary {
    /// Folds in one update's report.
    pub fn add(&mut self, report: &RunReport) {
        self.updates += 1;
        for e in &report.entries {
            let i = match self.lines.iter().position(|l| l.system == e.system && l.ran == e.ran) {
                Some(i) => i,
                None => {
                    // Next to the system's other outcome, ran first; new systems at the end.
                    let other = self.lines.iter().position(|l| l.system == e.system);
                    let i = other.map_or(self.lines.len(), |o| if e.ran { o } else { o + 1 });
                    let line =
                        SummaryLine { system: e.system, ran: e.ran, updates: 0, count: None, last_why: String::new() };
                    self.lines.insert(i, line);
                    i
                }
            };
            let line = &mut self.lines[i];
            line.updates += 1;
            line.last_why.clone_from(&e.why);
            if let Some((n, unit)) = e.count {
                line.count = Some((line.count.map_or(0, |c| c.0) + n, unit));
            }
        }
        self.warnings.extend(report.warnings.iter().cloned());
    }
    /// The line of `system` with outcome `ran`.
    pub fn line(&self, system: &str, ran: bool) -> Option<&SummaryLine> {
        self.lines.iter().find(|l| l.system == system && l.ran == ran)
    }
    /// How many updates ran `system`.
    pub fn runs(&self, system: &str) -> u32 {
        self.line(system, true).map_or(0, |l| l.updates)
    }
    /// The sum of `system`'s counts over the updates that ran it (0 if it counts nothing).
    pub fn count(&self, system: &str) -> u64 {
        self.line(system, true).and_then(|l| l.count).map_or(0, |c| c.0)
    }
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "run report over {} updates:", self.updates)?;
        for l in &self.lines {
            let outcome = if l.ran { "ran" } else { "skipped" };
            let times = format!("{} of {}", l.updates, self.updates);
            let total = l.count.map_or(String::new(), |(n, unit)| format!("{n} {unit} in all; last: "));
            writeln!(f, "{:<28} {outcome:<8} {times:<10} {total}{}", l.system, l.last_why)?;
        }
        for w in &self.warnings {
            writeln!(f, "warning: {w}")?;
        }
        Ok(())
    }
}

/// The scene's bounding sphere (geometry and lights), which distant and infinite lights need to
/// place their far sample points and to compute their power.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct SceneBounds {
    /// Bounding sphere, world space, metres.
    pub sphere: crate::light::SceneSphere,
}
