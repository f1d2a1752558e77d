//! `kelvin merge TILE.exr... -o FULL.exr [--exposure S]`: joins the tiles of `kelvin render --crop`
//! into the full image, which must be covered exactly once by tiles of one render (their recorded
//! provenance equal but for the tile).

use std::path::PathBuf;

use kelvin::render::film_io::read_exr_tile_and_provenance;
use kelvin::render::tiles::merge_tiles;

use super::CliError;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Tile EXRs written by `kelvin render --crop` (each records its region and the image size).
    #[arg(required = true)]
    tiles: Vec<PathBuf>,
    /// The full image: .exr (with a .png preview) or .png, as `kelvin render` writes it.
    #[arg(short, long)]
    output: PathBuf,
    /// PNG exposure in stops; automatic (as `kelvin render`'s) when absent.
    #[arg(long, value_parser = super::values::exposure())]
    exposure: Option<f32>,
}

pub fn run(args: MergeArgs) -> Result<(), CliError> {
    let read = args.tiles.iter().map(|p| read_exr_tile_and_provenance(p)).collect::<Result<Vec<_>, _>>()?;
    let (tiles, provenance): (Vec<_>, Vec<_>) = read.into_iter().unzip();
    // Tiles of one image differ in their window only: not in the build, scene, settings or frame.
    for (path, p) in args.tiles.iter().zip(&provenance).skip(1) {
        if let Some((key, theirs, first)) = p.difference(&provenance[0], &["tile"]) {
            return Err(format!(
                "{}: its {key} is {theirs}, {}'s is {first}: tiles of different renders (or builds) do not merge",
                path.display(),
                args.tiles[0].display()
            )
            .into());
        }
    }
    let (width, height, rgb) = merge_tiles(&tiles)?;
    let exposure = args.exposure.unwrap_or_else(|| kelvin::render::film_io::auto_exposure(&rgb));
    let mut merged = provenance.into_iter().next().unwrap_or_default().without("tile");
    // A PNG's pixels depend on its exposure too (as `kelvin render` records it).
    if args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        merged = merged.with("exposure", args.exposure.map_or("auto".to_owned(), |e| e.to_string()));
    }
    super::render::write_outputs(&args.output, width, height, &rgb, exposure, &merged)?;
    println!("merged {} tiles into {width}x{height}", tiles.len());
    Ok(())
}
