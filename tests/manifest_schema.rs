//! The manifest has one definition: its settings are the commands' flags and its JSON Schema is
//! generated from them. The committed docs/manifest.schema.json is what `kelvin batch --schema`
//! prints (regenerate it when a flag changes), it accepts the README's manifests and refuses
//! broken ones, and a flag new to `kelvin render` is a setting without any manifest code.

mod common;

use std::process::Command;

use serde_json::Value;

use common::files::{TempDir, test_data};

fn kelvin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().unwrap()
}

/// The errors of `value` against `schema`, for the keywords the generated schema uses.
fn errors(schema: &Value, value: &Value, at: &str, out: &mut Vec<String>) {
    let fail = |out: &mut Vec<String>, why: String| out.push(format!("{at}: {why}"));
    if let Some(types) = schema.get("type") {
        let types: Vec<&str> = match types {
            Value::String(t) => vec![t.as_str()],
            Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
            _ => vec![],
        };
        let is = |t: &str| match t {
            "object" => value.is_object(),
            "array" => value.is_array(),
            "string" => value.is_string(),
            "number" => value.is_number(),
            "integer" => value.is_u64() || value.is_i64(),
            "boolean" => value.is_boolean(),
            _ => false,
        };
        if !types.iter().any(|t| is(t)) {
            fail(out, format!("{value} is not {types:?}"));
        }
    }
    if let Some(e) = schema.get("enum").and_then(Value::as_array).filter(|e| !e.contains(value)) {
        fail(out, format!("{value} is not one of {e:?}"));
    }
    if let Some(c) = schema.get("const").filter(|c| *c != value) {
        fail(out, format!("{value} is not {c}"));
    }
    if let (Some(min), Some(v)) = (schema.get("minimum").and_then(Value::as_f64), value.as_f64())
        && v < min
    {
        fail(out, format!("{v} < {min}"));
    }
    if let Some(object) = value.as_object() {
        let properties = schema.get("properties").and_then(Value::as_object);
        for key in schema.get("required").and_then(Value::as_array).into_iter().flatten() {
            if !object.contains_key(key.as_str().unwrap()) {
                fail(out, format!("{key} is required"));
            }
        }
        for (key, v) in object {
            match properties.and_then(|p| p.get(key)) {
                Some(s) => errors(s, v, &format!("{at}/{key}"), out),
                None if schema.get("additionalProperties") == Some(&Value::Bool(false)) => {
                    fail(out, format!("unknown key {key:?}"))
                }
                None => {}
            }
        }
        if let Some(not) = schema.get("not") {
            let mut inner = Vec::new();
            errors(not, value, at, &mut inner);
            if inner.is_empty() {
                fail(out, "matches what it must not".into());
            }
        }
    }
    if let (Some(items), Some(array)) = (schema.get("items"), value.as_array()) {
        for (i, v) in array.iter().enumerate() {
            errors(items, v, &format!("{at}/{i}"), out);
        }
    }
    if let Some(one_of) = schema.get("oneOf").and_then(Value::as_array) {
        let mut why = Vec::new();
        let passing = one_of
            .iter()
            .filter(|s| {
                let mut inner = Vec::new();
                errors(s, value, at, &mut inner);
                why.extend(inner.iter().cloned());
                inner.is_empty()
            })
            .count();
        if passing != 1 {
            fail(out, format!("matches {passing} of the oneOf alternatives ({})", why.join("; ")));
        }
    }
}

fn schema() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/manifest.schema.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn the_committed_schema_is_the_generated_one() {
    let out = kelvin(&["batch", "--schema"]);
    assert!(out.status.success());
    let generated: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        generated == schema(),
        "docs/manifest.schema.json is stale: run `kelvin batch --schema > docs/manifest.schema.json`"
    );
}

#[test]
fn the_schema_accepts_the_readmes_manifests_and_refuses_broken_ones() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let manifests: Vec<Value> = readme
        .split("```json")
        .skip(1)
        .filter_map(|block| serde_json::from_str::<Value>(block.split("```").next()?).ok())
        .filter(|v| v.get("jobs").is_some())
        .collect();
    assert!(manifests.len() >= 2, "the README's render and bake manifests");
    let schema = schema();
    for m in &manifests {
        let mut e = Vec::new();
        errors(&schema, m, "", &mut e);
        assert!(e.is_empty(), "{e:?} in {m}");
    }
    for (broken, says) in [
        (r#"{"jobs": [{"output": "a.exr", "settings": {"sise": 3}}]}"#, "unknown key \"sise\""),
        (r#"{"jobs": [{"output": "a.exr", "settings": {"integrator": "bidir"}}]}"#, "not one of"),
        (r#"{"jobs": [{"bake": "lightmaps", "scene": "a.glb"}]}"#, "\"output\" is required"),
        (r#"{"version": 2, "jobs": []}"#, "is not 1"),
    ] {
        let mut e = Vec::new();
        errors(&schema, &serde_json::from_str(broken).unwrap(), "", &mut e);
        assert!(e.iter().any(|e| e.contains(says)), "{broken}: {e:?}");
    }
}

/// Settings are the flags: `sky_intensity`, `biased_reuse` and `time`, which the hand-written
/// settings lacked, reach `kelvin render`; an unknown one is the parser's error; a newer manifest
/// version is refused.
#[test]
fn every_render_flag_is_a_setting() {
    let dir = TempDir::new("manifest", "flags");
    let scene = test_data("gltf/bevy/CornellBox.glb");
    let write = |body: &str| {
        let path = dir.join("jobs.json");
        std::fs::write(&path, body).unwrap();
        path.to_str().unwrap().to_owned()
    };
    let m = write(&format!(
        r#"{{"version": 1, "jobs": [{{"scene": "{}", "output": "a.exr", "size": "8x8",
            "settings": {{"light_sampler": "restir", "biased_reuse": true, "sky": "48.86,2.35,2024-06-21T10:00",
                          "sky_intensity": 0.5, "mis": false}}}}]}}"#,
        scene.display()
    ));
    let plan: Value = serde_json::from_slice(&kelvin(&["batch", &m, "--plan"]).stdout).unwrap();
    let args: Vec<&str> = plan["jobs"][0]["args"].as_array().unwrap().iter().map(|a| a.as_str().unwrap()).collect();
    for flag in ["--biased-reuse", "--sky-intensity", "--no-mis", "--light-sampler"] {
        assert!(args.contains(&flag), "{flag} in {args:?}");
    }
    assert!(plan["jobs"][0]["error"].is_null(), "{}", plan["jobs"][0]);
    let m = write(r#"{"jobs": [{"output": "b.exr", "settings": {"sise": 8, "crop": "0,0,1,1"}}]}"#);
    let plan: Value = serde_json::from_slice(&kelvin(&["batch", &m, "--plan"]).stdout).unwrap();
    let error = plan["jobs"][0]["error"].as_str().unwrap();
    assert!(error.contains("crop: set by the job itself") || error.contains("'--sise'"), "{error}");
    let out = kelvin(&["batch", &write(r#"{"version": 7, "jobs": []}"#)]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("manifest version 7; this kelvin reads version 1"));
}
