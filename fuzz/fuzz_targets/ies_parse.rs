//! IES LM-63: bytes -> `IesProfile::parse` (as `from_file` reads them: lossy UTF-8) -> flux, beam angle and a
//! goniometric light resolved from the profile, its power and a few emission samples. A parse or resolve error is
//! fine; a panic, or a non-finite or negative flux from an accepted file, is a crash.
#![no_main]

use std::sync::Arc;

use glam::{Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::GoniometricLight;
use kelvin::scene::ies::IesProfile;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(profile) = IesProfile::parse(&text, "fuzz.ies") else { return };
    let flux = profile.integrated_flux_lm();
    assert!(flux.is_finite() && flux >= 0.0, "integrated flux {flux}");
    let _ = profile.beam_angle_deg();
    let _ = profile.candela_dir(Vec3::new(0.3, -0.2, -1.0));
    let Ok(light) = GoniometricLight::from_ies(Arc::new(profile)).resolve(&Transform::IDENTITY) else { return };
    let phi = light.phi();
    assert!(phi.is_finite() && phi >= 0.0, "light power {phi} (flux {flux})");
    for u in [Vec2::new(0.1, 0.2), Vec2::new(0.5, 0.5), Vec2::new(0.99, 0.01)] {
        if let Some((w, pdf)) = light.sample_emission_direction(u) {
            assert!(w.is_finite() && pdf.is_finite() && pdf >= 0.0, "sample {w} pdf {pdf}");
            let _ = light.pdf_emission_direction(w);
            let _ = light.intensity_toward(w);
        }
    }
});
