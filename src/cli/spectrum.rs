//! `kelvin spectrum <SPEC> [--json] [--plot FILE]`.

use std::path::PathBuf;

use kelvin::report::plot::{PlotSpec, Series, line_plot};
use kelvin::spectrum::{Spectrum, SpectrumSummary};

use super::CliError;

#[derive(clap::Args)]
pub struct SpectrumArgs {
    /// blackbody:<K>, graybody:<K>:<emissivity>, illuminant:<name>, daylight:<K>, or a CSV file of nm,value rows.
    spec: String,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Draw the spectrum (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

pub fn run(args: SpectrumArgs) -> Result<(), CliError> {
    let spectrum = Spectrum::parse(&args.spec)?;
    let summary = SpectrumSummary::of(&spectrum);
    if args.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        println!("spectrum           {}", args.spec);
        print!("{summary}");
    }
    if let Some(path) = args.plot {
        let (lo, hi) = spectrum.support_nm().map_or((360.0, 830.0), |(a, b)| (a.max(300.0), b.min(1000.0)));
        let n = ((hi - lo) as usize).max(1);
        let points = (0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64).map(|l| (l, spectrum.eval(l))).collect();
        let spec = PlotSpec {
            title: &args.spec,
            x_label: "wavelength (nm)",
            y_label: "relative spectral power",
            equal_aspect: false,
        };
        line_plot(&path, &spec, &[Series { name: String::new(), points }])?;
        if !args.json {
            println!("plot               {}", path.display());
        }
    }
    Ok(())
}
