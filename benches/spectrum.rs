//! Spectrum evaluation: sampled Planck at 4 wavelengths, and a tabulated SPD to XYZ.

use criterion::{Criterion, criterion_group, criterion_main};
use kelvin::spectrum::{CIE_1931, SampledWavelengths, Spectrum};
use std::hint::black_box;

fn sampled_planck(c: &mut Criterion) {
    let bb = Spectrum::blackbody(3200.0).unwrap();
    let mut u = 0.1234f32;
    c.bench_function("planck_4_wavelengths", |b| {
        b.iter(|| {
            u = (u + 0.618_034).fract();
            let w = SampledWavelengths::sample_visible(black_box(u));
            black_box(w.eval(&bb))
        })
    });
}

fn tabulated_to_xyz(c: &mut Criterion) {
    let f11 = Spectrum::illuminant("F11").unwrap();
    c.bench_function("tabulated_spd_to_xyz", |b| b.iter(|| black_box(black_box(&f11).xyz_integral(&CIE_1931))));
}

criterion_group!(benches, sampled_planck, tabulated_to_xyz);
criterion_main!(benches);
