//! A bake's files: per lightmap `<name>.exr` (linear f32) and `<name>.ktx2` (B10G11R11_UFLOAT,
//! zstd-supercompressed, as Bevy's own lightmaps), and `lightmaps.json`, which maps each lightmap
//! to its mesh, node and files, the `uv_rect` Bevy's `Lightmap` takes and a `lightmap_exposure`.
//! An irradiance volume is one 3D KTX2 (E5B9G9R9_UFLOAT, zstd, Bevy's layout) and a JSON file
//! beside it with the light probe's transform.

use std::path::{Path, PathBuf};

use serde_json::json;

use super::ktx2::{self, Format, Supercompression, Texture};
use super::volume::IrradianceVolume;
use super::{BakeError, BakeReport, BakedLight, LightmapOptions, TexelState};
use crate::render::film_io::{ImageIoError, write_exr, write_file};

/// The name of the index file in the output folder.
pub const LIGHTMAPS_JSON: &str = "lightmaps.json";
/// Zstandard level of the KTX2 files: a few times smaller than raw texels, fast to write.
const ZSTD_LEVEL: i32 = 9;

/// Writes every lightmap of `report` into `dir` (created if missing), then `lightmaps.json` last,
/// so that a folder with the index holds a finished bake. Returns the files written.
pub fn write_lightmaps(dir: &Path, report: &BakeReport, opts: &LightmapOptions) -> Result<Vec<PathBuf>, BakeError> {
    let io = |path: &Path, e: std::io::Error| ImageIoError::Io {
        what: path.display().to_string(),
        msg: e.to_string(),
        kind: e.kind(),
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let mut written = Vec::new();
    let mut entries = serde_json::Map::new();
    for map in &report.lightmaps {
        let side = map.size as usize;
        let (exr, ktx2) = (dir.join(format!("{}.exr", map.name)), dir.join(format!("{}.ktx2", map.name)));
        write_exr(&exr, side, side, &map.texels)?;
        let texture =
            Texture { format: Format::B10G11R11, width: map.size, height: map.size, depth: 0, texels: &map.texels };
        let bytes = ktx2::encode(&texture, Supercompression::Zstd(ZSTD_LEVEL))?;
        write_file(&ktx2, &ktx2.display().to_string(), &bytes)?;
        let count = |s: TexelState| map.state.iter().filter(|t| **t == s).count();
        let file = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
        entries.insert(
            map.name.clone(),
            json!({
                "mesh": map.mesh_name,
                "node": map.node_name,
                "size": map.size,
                "image": file(&ktx2),
                "exr": file(&exr),
                "uv_rect": [0.0, 0.0, 1.0, 1.0],
                // Texels are nit, Bevy's own photometric units: no rescaling.
                "lightmap_exposure": 1.0,
                "mean_luminance": map.mean_luminance(),
                "texels": { "baked": count(TexelState::Baked), "filled": count(TexelState::Filled), "empty": count(TexelState::Empty) },
                "leaked_samples": map.leaked_samples,
            }),
        );
        written.extend([exr, ktx2]);
    }
    let index = json!({
        "generator": format!("kelvin {}", env!("CARGO_PKG_VERSION")),
        "camera_ev100": camera_ev100(report),
        "texel": "irradiance / pi (the radiance a white Lambertian surface reflects), linear sRGB, nit (cd/m^2); rows top to bottom as glTF uv (v = 0 at the top)",
        "light": match opts.light { BakedLight::All => "all", BakedLight::Indirect => "indirect" },
        "size": opts.size,
        "texels_per_unit": opts.texels_per_unit,
        "spp": report.stats.spp,
        "max_depth": opts.depth.max_depth,
        "lightmaps": entries,
        "skipped": report.skipped,
    });
    let path = dir.join(LIGHTMAPS_JSON);
    let text = serde_json::to_string_pretty(&index).unwrap_or_default() + "\n";
    write_file(&path, &path.display().to_string(), text.as_bytes())?;
    written.push(path);
    Ok(written)
}

/// The EV100 that an averaging reflected-light meter (calibration K = 12.5 cd s/m^2 at ISO 100)
/// reads off the baked surfaces, EV100 = log2(L 100 / K): Bevy's `Exposure { ev100 }` that shows
/// them near mid-grey. L is the luminance they show, texel times albedo (Bevy's `lightmap *
/// diffuse_color`), averaged over their area, so a small lamp with a map as large as the room's
/// weighs as little as it covers. Emission is left out: a light in view would set the exposure.
/// None without a lit texel.
fn camera_ev100(report: &BakeReport) -> Option<f32> {
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for map in &report.lightmaps {
        for (k, _) in map.state.iter().enumerate().filter(|(_, s)| **s == TexelState::Baked) {
            let shown = super::lightmap::luminance(map.texels[k] * map.albedo[k]) as f64;
            (sum, area) = (sum + shown * map.area[k] as f64, area + map.area[k] as f64);
        }
    }
    (sum > 0.0).then(|| (sum / area * 100.0 / 12.5).log2() as f32)
}

/// Writes `volume` as a 3D KTX2 at `path` (its folder created if missing; E5B9G9R9_UFLOAT, zstd,
/// Bevy's layout) and, beside it (`.json`), the `Transform` Bevy's light probe needs (the volume is
/// a unit cube it scales and places) and the intensity (1: texels are nit). Returns the files
/// written.
pub fn write_volume(path: &Path, volume: &IrradianceVolume) -> Result<Vec<PathBuf>, BakeError> {
    let r = volume.resolution;
    let atlas = volume.atlas();
    let texture = Texture { format: Format::E5B9G9R9, width: r.x, height: 2 * r.y, depth: 3 * r.z, texels: &atlas };
    let bytes = ktx2::encode(&texture, Supercompression::Zstd(ZSTD_LEVEL))?;
    let info = json!({
        "generator": format!("kelvin {}", env!("CARGO_PKG_VERSION")),
        "voxels": path.file_name().map(|n| n.to_string_lossy().into_owned()),
        "resolution": r.to_array(),
        "transform": { "translation": volume.center().to_array(), "scale": volume.scale().to_array() },
        "intensity": 1.0,
        "side": "irradiance / pi about the axis, linear sRGB, nit; (Rx, 2Ry, 3Rz) texels, side S of voxel (x, y, z) at (x, y + Ry [S negative], z + Rz axis(S))",
        "inside_voxels": volume.inside,
    });
    let json_path = path.with_extension("json");
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        let io = |e: std::io::Error| ImageIoError::Io {
            what: dir.display().to_string(),
            msg: e.to_string(),
            kind: e.kind(),
        };
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    write_file(path, &path.display().to_string(), &bytes)?;
    let text = serde_json::to_string_pretty(&info).unwrap_or_default() + "\n";
    write_file(&json_path, &json_path.display().to_string(), text.as_bytes())?;
    Ok(vec![path.to_path_buf(), json_path])
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::bake::Lightmap;

    /// A lightmap of `texels` texels, each `nit` on `area` m^2 of albedo `albedo`.
    fn map(texels: usize, nit: f32, area: f32, albedo: f32) -> Lightmap {
        Lightmap {
            name: String::new(),
            mesh_name: None,
            node_name: None,
            size: 1,
            texels: vec![Vec3::splat(nit); texels],
            std_error: vec![Vec3::ZERO; texels],
            state: vec![TexelState::Baked; texels],
            leaked_samples: 0,
            area: vec![area; texels],
            albedo: vec![Vec3::splat(albedo); texels],
        }
    }

    /// A 1 m^2 lamp (100 nit, white) baked at as many texels as a 99 m^2 room (1 nit, albedo 0.5)
    /// covers 1% of what the camera sees: the meter reads (0.01 100 + 0.99 0.5) nit = 1.495 nit, not
    /// the texels' mean after albedo (25.25 nit) nor their plain mean (50.5 nit).
    #[test]
    fn the_meter_weighs_surfaces_by_area_after_albedo() {
        let n = 64;
        let lamp = map(n, 100.0, 1.0 / n as f32, 1.0);
        let room = map(n, 1.0, 99.0 / n as f32, 0.5);
        let report = BakeReport { lightmaps: vec![lamp, room], ..BakeReport::default() };
        let ev = camera_ev100(&report).unwrap();
        let want = (1.495f32 * 100.0 / 12.5).log2();
        assert!((ev - want).abs() < 1e-3, "EV100 {ev}, want {want}");
        // Filled and empty texels are not surfaces the bake saw.
        let mut dark = map(n, 0.0, 1.0, 1.0);
        dark.state.fill(TexelState::Filled);
        let report = BakeReport {
            lightmaps: vec![report.lightmaps[0].clone(), report.lightmaps[1].clone(), dark],
            ..BakeReport::default()
        };
        assert!((camera_ev100(&report).unwrap() - want).abs() < 1e-3);
        assert_eq!(camera_ev100(&BakeReport::default()), None);
    }
}
