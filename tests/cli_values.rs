//! Every option and argument of the `kelvin` program, given a bad value, is refused before any work
//! with a message that names the option (or the file) and the value, and says what is accepted.
//! The options are read from each subcommand's `--help`, so an option added without a case here
//! fails this test.

use std::collections::BTreeSet;
use std::process::Command;

fn kelvin(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("kelvin runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// The `--long` options of `kelvin SUBCOMMAND` that take a value, from its help.
fn value_options(subcommand: &[&str]) -> BTreeSet<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_kelvin")).args(subcommand).arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout).into_owned();
    let mut options = BTreeSet::new();
    for line in help.lines().map(str::trim_start).filter(|l| l.starts_with('-')) {
        let Some(long) = line.split_whitespace().find(|w| w.starts_with("--")) else { continue };
        let takes_value = line.split_whitespace().skip_while(|w| *w != long).nth(1).is_some_and(|w| w.starts_with('<'));
        if takes_value && long != "--help" {
            options.insert(long.trim_end_matches(',').to_owned());
        }
    }
    options
}

/// (subcommand, option, bad value, what the message must also say). The value itself must
/// appear in the message too.
const BAD_OPTIONS: &[(&[&str], &str, &str, &str)] = &[
    (&["render"], "--spp", "0", "1..=1048576"),
    (&["render"], "--time", "-1", "[0, 10000000)"),
    (&["render"], "--time", "inf", "[0, 10000000)"),
    (&["render"], "--size", "0x10", "1..=16384"),
    (&["render"], "--env", "no-such-map.exr", "file not found"),
    (&["render"], "--env-intensity", "nan", "[0, 1000000000000]"),
    (&["render"], "--env-intensity", "-2", "[0, 1000000000000]"),
    (&["render"], "--sky", "95,0,2024-06-21T10:00", "latitude"),
    (&["render"], "--sky-intensity", "-1", "[0, 1000000000000]"),
    (&["render"], "--integrator", "bidir", "possible values"),
    (&["render"], "--max-depth", "2000", "0..=1024"),
    (&["render"], "--roulette-depth", "-1", "0..=1024"),
    (&["render"], "--light-sampler", "magic", "possible values"),
    (&["render"], "--color", "purple", "possible values"),
    (&["render"], "--pattern", "halton", "possible values"),
    (&["render"], "--candidates", "0", "1..=4096"),
    (&["render"], "--neighbours", "1000", "0..=256"),
    (&["render"], "--radius", "0", "1..=16384"),
    (&["render"], "--seed", "-3", "invalid digit"),
    (&["render"], "--threads", "0", "1..=1024"),
    (&["render"], "--exposure", "nan", "[-64, 64]"),
    (&["render"], "--exposure", "100", "[-64, 64]"),
    (&["render"], "--environment-at", "0,nan,0", "three finite numbers"),
    (&["render"], "--crop", "4,4,2,2", "is empty"),
    (&["render"], "--frames", "5..2", "5..2"),
    (&["render"], "--fps", "0", "(0, 1000000]"),
    (&["render"], "--animation", "no-such-clip", "animation"),
    (&["render"], "--output", "image.txt", "use .exr or .png"),
    (&["merge", "tile.exr"], "--exposure", "inf", "[-64, 64]"),
    (&["merge", "tile.exr"], "--output", "", "output"),
    (&["batch", "jobs.json"], "--threads", "4096", "1..=1024"),
    (&["batch", "jobs.json"], "--task", "x", "invalid digit"),
    (&["batch", "jobs.json"], "--frames", "1-5x0", "step of 0"),
    (&["report", "accuracy"], "--threads", "0", "1..=1024"),
    (&["bench", "lights"], "--counts", "0", "1..=100000000"),
    (&["bench", "lights"], "--points", "0", "1..=16777216"),
    (&["bench", "lights"], "--samples", "0", "1..=16777216"),
    (&["bench", "lights"], "--frames", "0", "1..=100000"),
    (&["bench", "lights"], "--move-step", "nan", "[0, 1000000]"),
    (&["bench", "lights"], "--panel-tiles", "5000", "0..=4096"),
    (&["bench", "lights"], "--seed", "x", "invalid digit"),
    (&["bench", "render"], "--size", "64", "WIDTHxHEIGHT"),
    (&["bench", "render"], "--spp", "0", "1..=1048576"),
    (&["bench", "render"], "--scenes", "no-such-scene", "no-such-scene"),
    (&["bench", "render"], "--repeat", "0", "1..=1000"),
    (&["bench", "render"], "--threads", "0", "1..=1024"),
    (&["bench", "render"], "--light-sampler", "magic", "possible values"),
    (&["bench", "render"], "--integrator", "bidir", "possible values"),
    (&["bench", "render"], "--max-depth", "2000", "0..=1024"),
    (&["bake", "lightmaps"], "--size", "0", "1..=4096"),
    (&["bake", "lightmaps"], "--spp", "0", "1..=1048576"),
    (&["bake", "lightmaps"], "--max-depth", "2000", "0..=1024"),
    (&["bake", "lightmaps"], "--light", "direct", "possible values"),
    (&["bake", "lightmaps"], "--pattern", "random", "possible values"),
    (&["bake", "lightmaps"], "--seed", "-3", "invalid digit"),
    (&["bake", "lightmaps"], "--threads", "0", "1..=1024"),
    (&["bake", "lightmaps"], "--time", "-1", "[0, 10000000)"),
    (&["bake", "lightmaps"], "--texels-per-unit", "0", "[0.000001, 1000000]"),
    (&["bake", "lightmaps"], "--part", "0/2", "1 <= K <= N"),
    (&["bake", "lightmaps"], "--env", "no-such-map.exr", "file not found"),
    (&["bake", "lightmaps"], "--env-intensity", "-2", "[0, 1000000000000]"),
    (&["bake", "lightmaps"], "--sky", "95,0,2024-06-21T10:00", "latitude"),
    (&["bake", "lightmaps"], "--sky-intensity", "nan", "[0, 1000000000000]"),
    (&["bake", "volume"], "--part", "3/2", "1 <= K <= N"),
    (&["bake", "volume"], "--node", "no-such-node", "nodes with meshes"),
    (&["bake", "volume"], "--env", "no-such-map.exr", "file not found"),
    (&["bake", "volume"], "--env-intensity", "inf", "[0, 1000000000000]"),
    (&["bake", "volume"], "--sky", "0,200,2024-06-21T10:00", "longitude"),
    (&["bake", "volume"], "--sky-intensity", "-1", "[0, 1000000000000]"),
    (&["bake", "volume"], "--time", "nan", "[0, 10000000)"),
    (&["bake", "volume"], "--resolution", "0,2,2", "each in 1..=128"),
    (&["bake", "volume"], "--resolution", "2,2", "three whole numbers"),
    (&["bake", "volume"], "--bounds", "1,1,1,0,0,0", "must be below"),
    (&["bake", "volume"], "--bounds", "0,0,0,1,nan,1", "six finite numbers"),
    (&["bake", "volume"], "--spp", "0", "1..=1048576"),
    (&["bake", "volume"], "--max-depth", "2000", "0..=1024"),
    (&["bake", "volume"], "--light", "direct", "possible values"),
    (&["bake", "volume"], "--pattern", "sobel", "possible values"),
    (&["bake", "volume"], "--seed", "-3", "invalid digit"),
    (&["bake", "volume"], "--threads", "0", "1..=1024"),
];

/// Options whose value is a path the command writes or a folder it reads at the end of its work,
/// or a name looked up in a file, checked where it is used; the reason is what a reader of this list
/// needs.
const PATH_OPTIONS: &[(&[&str], &str, &str)] = &[
    (&["spectrum"], "--plot", "the plot's path; the extension is checked with the spectrum's"),
    (&["ies"], "--plot", "the plot's path"),
    (&["report", "accuracy"], "--out", "an output folder, created"),
    (&["report", "accuracy"], "--data", "read only for the env-map scene"),
    (&["bench", "lights"], "--out", "an output folder, created"),
    (&["bench", "render"], "--data", "read when each scene loads"),
    (&["batch"], "--log", "the task's log, opened (its folder created) once the manifest is planned"),
    (&["render"], "--log", "the task's log, opened (its folder created) before the render (tests/cli_farm.rs)"),
    (&["batch"], "--job", "a job's name, looked up in the manifest (tests/cli_farm.rs: an unknown one is refused)"),
    (&["bake", "lightmaps"], "--output", "an output folder, created after the bake"),
    (&["bake", "volume"], "--output", "the .ktx2 written after the bake; its extension is checked first"),
];

/// Arguments that make a run of `subcommand` cheap and valid, apart from the option under test.
fn base_args(subcommand: &[&str], option: &str) -> Vec<&'static str> {
    match subcommand[0] {
        "render" => {
            let mut base = vec![];
            if option != "--size" {
                base.extend(["--size", "8x8"]);
            }
            if option != "--spp" {
                base.extend(["--spp", "1"]);
            }
            if option != "--output" {
                base.extend(["-o", "never-written.png"]);
            }
            base
        }
        "merge" if option != "--output" => vec!["-o", "never-written.exr"],
        // Options checked once the scene loads (files, the sky's place, a node) need a whole command.
        "bake" if ["--env", "--sky", "--node"].contains(&option) => {
            let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bevy/CornellBox.glb");
            match subcommand[1] {
                "volume" => vec![scene, "-o", "never-written.ktx2", "--resolution", "1,1,1", "--spp", "1"],
                _ => vec![scene, "-o", "never-written", "--size", "1", "--spp", "1"],
            }
        }
        _ => vec![],
    }
}

#[test]
fn every_option_with_a_bad_value_is_refused_naming_the_option_the_value_and_the_range() {
    let subcommands: &[&[&str]] = &[
        &["spectrum"],
        &["ies"],
        &["render"],
        &["batch"],
        &["merge"],
        &["report", "accuracy"],
        &["bench", "lights"],
        &["bench", "render"],
        &["bake", "lightmaps"],
        &["bake", "volume"],
    ];
    for &sub in subcommands {
        let name = |o: &str| format!("{} {o}", sub.join(" "));
        let covered: BTreeSet<String> = BAD_OPTIONS
            .iter()
            .filter(|c| c.0[..sub.len().min(c.0.len())] == *sub && c.0[0] == sub[0])
            .map(|c| c.1)
            .chain(PATH_OPTIONS.iter().filter(|c| c.0 == sub).map(|c| c.1))
            .map(str::to_owned)
            .collect();
        for option in value_options(sub) {
            assert!(covered.contains(&option), "{}: no bad-value case in BAD_OPTIONS or PATH_OPTIONS", name(&option));
        }
    }
    for &(sub, option, bad, says) in BAD_OPTIONS {
        // --option=value, so that a value like -1 is not read as a flag.
        let given = format!("{option}={bad}");
        let mut args: Vec<&str> = sub.to_vec();
        args.extend(base_args(sub, option));
        args.push(&given);
        // An animation is chosen by name in an animated scene.
        let lamp = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/kelvin/animated_lamp.gltf");
        if option == "--animation" {
            args.extend([lamp, "--frames", "0"]);
        }
        let (ok, err) = kelvin(&args);
        let line = args.join(" ");
        assert!(!ok, "{line}: accepted");
        assert!(!err.contains("panicked"), "{line}: {err}");
        // The error line (a scene's load summary may come first).
        let first = err.lines().find(|l| l.starts_with("error")).unwrap_or_default();
        assert!(err.contains(says), "{line}: the message says what is accepted ({says}): {err}");
        assert!(bad.is_empty() || first.contains(bad), "{line}: the message names the value: {first}");
        // The option by its name: a message naming only the value leaves a command line with
        // several values (a path given to --env and to the scene, say) ambiguous.
        assert!(first.contains(option), "{line}: the message names the option {option}: {first}");
    }
}

/// Arguments (not options) with bad values: the message names the file or value, says whether
/// reading or writing failed, and prints ranges as a person writes them.
#[test]
fn bad_arguments_name_the_file_and_whether_reading_or_writing_failed() {
    let cases: &[(&[&str], &str)] = &[
        (&["spectrum", "blackbody:-5"], "temperature (K) = -5 is outside (0, 1000000000]"),
        (&["spectrum", "graybody:3000:2"], "emissivity = 2 is outside [0, 1]"),
        (&["spectrum", "no-such.csv"], "no-such.csv: cannot read"),
        (&["ies", "no-such.ies"], "no-such.ies: cannot read"),
        (&["merge", "no-such-tile.exr", "-o", "never-written.exr"], "no-such-tile.exr: cannot read"),
        (&["batch", "no-such-jobs.json"], "no-such-jobs.json: cannot read"),
        (&["render", "no-such-scene.glb", "--size", "8x8", "-o", "never-written.png"], "no-such-scene.glb"),
        (&["render", "--size", "8x8", "--spp", "1", "-o", "/proc/no-such-dir/x.png"], "cannot write"),
        (&["report", "accuracy", "no-such-scene", "--out", "never-written"], "no-such-scene"),
        (&["bake", "lightmaps", "no-such-scene.glb", "-o", "never-written"], "no-such-scene.glb: file not found"),
        // An installed crate has no tests/data: the benchmark says where the scenes are.
        (&["bench", "render", "--data", "no-such-data", "--scenes", "sponza"], "--data no-such-data: not a folder"),
    ];
    for &(args, says) in cases {
        let (ok, err) = kelvin(args);
        let line = args.join(" ");
        assert!(!ok && !err.contains("panicked"), "{line}: {err}");
        assert!(err.contains(says), "{line}: expected '{says}' in: {err}");
    }
    assert!(!std::path::Path::new("never-written.exr").exists() && !std::path::Path::new("never-written").exists());
}
