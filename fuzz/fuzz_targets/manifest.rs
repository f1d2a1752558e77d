//! Batch manifests, as `kelvin batch` (and `--plan`, `--task N`, the Ray driver) read them: bytes
//! (lossy UTF-8) -> `plan_text_selected` (every job) with the manifest in `tests/data`, so that
//! relative scenes, env maps and IES files can name real files. The `kelvin` program's own `cli` module is compiled in, since
//! the manifest is parsed by its `render` and `bake` argument definitions. An error is fine; a panic
//! is a crash, and so is an accepted job that breaks the plan's promises: a render job has a .exr or
//! .png output, a size and arguments that parse again; no two accepted jobs write one file (a
//! chunk writes each of its frames); the plan prints as JSON. libFuzzer's slow-unit reports count
//! too: the first hour found a manifest whose plan took 416 s under ASan.
#![no_main]

#[allow(dead_code, unused_imports)]
#[path = "../../src/cli/mod.rs"]
mod cli;

use std::collections::HashSet;
use std::path::PathBuf;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/fuzz_manifest.json"));
    let every = cli::manifest::Selection::default();
    let Ok(jobs) = cli::manifest::plan_text_selected(&text, &path, &every) else { return };
    serde_json::to_string(&serde_json::json!({ "jobs": jobs })).expect("the plan prints");
    let mut outputs = HashSet::new();
    for job in jobs.iter().filter(|j| j.error.is_none()) {
        for output in job.outputs() {
            assert!(outputs.insert(output.clone()), "two accepted jobs write {}", output.display());
        }
        if job.command == "render" {
            let ext = job.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
            assert!(matches!(ext.as_deref(), Some("exr" | "png")), "output {}", job.output.display());
            assert!(job.width > 0 && job.height > 0, "size {}x{}", job.width, job.height);
            job.render_args(&job.output).expect("an accepted job's arguments parse again");
        } else {
            assert!(job.parts >= 1 && job.parts_dir.is_some(), "bake parts");
        }
    }
});
