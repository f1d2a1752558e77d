//! `kelvin ies <file.ies> [--json] [--plot FILE]`.

use std::path::PathBuf;

use kelvin::report::plot::{PlotSpec, Series, line_plot};
use kelvin::scene::ies::{IesProfile, IesSummary, plane_names};

use super::CliError;

#[derive(clap::Args)]
pub struct IesArgs {
    /// An IES LM-63 photometric file (1986, 1991, 1995, 2002 or 2019).
    file: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Draw polar candela curves in the two vertical planes (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

pub fn run(args: IesArgs) -> Result<(), CliError> {
    let profile = IesProfile::from_file(&args.file)?;
    let summary = IesSummary::of(&profile);
    if args.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        println!("file               {}", args.file.display());
        print!("{summary}");
    }
    if let Some(path) = args.plot {
        // Polar curves: nadir points down, x = I sin(theta), y = -I cos(theta).
        let series: Vec<Series> = plane_names(profile.photometric_type())
            .iter()
            .zip([0.0, 90.0])
            .map(|(name, azimuth)| Series {
                name: name.to_string(),
                points: profile
                    .plane_curve(azimuth, 720)
                    .into_iter()
                    .map(|(theta, cd)| {
                        let (s, c) = theta.to_radians().sin_cos();
                        (cd * s, -cd * c)
                    })
                    .collect(),
            })
            .collect();
        let title =
            args.file.file_name().map_or_else(|| args.file.display().to_string(), |n| n.to_string_lossy().into());
        let spec = PlotSpec { title: &title, x_label: "cd", y_label: "cd", equal_aspect: true };
        line_plot(&path, &spec, &series)?;
        if !args.json {
            println!("plot               {}", path.display());
        }
    }
    Ok(())
}
