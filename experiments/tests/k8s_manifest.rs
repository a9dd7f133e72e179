//! The Kubernetes manifest of a sweep is a valid `batch/v1` Indexed Job: checked against a
//! schema excerpt written from the Kubernetes API reference (`data/indexed-job.schema.json`)
//! by a small validator of the JSON-schema keywords it uses. Negative controls: manifests
//! without `completionMode`, with a string `completions`, a restart policy a Job refuses, a
//! misspelt field or a name that is not a DNS label fail.

use experiments::sweep::{k8s_manifest, Job, K8sOptions, Sweep, SweepInfo, SWEEP_FORMAT};
use serde_json::{json, Value};

/// The schema excerpt.
fn schema() -> Value {
    let text = include_str!("data/indexed-job.schema.json");
    serde_json::from_str(text).expect("the schema is JSON")
}

/// Every violation of `schema` in `value` at `path`, pushed to `errors`.
fn validate(schema: &Value, value: &Value, path: &str, errors: &mut Vec<String>) {
    let mut fail = |m: String| errors.push(format!("{path}: {m}"));
    if let Some(c) = schema.get("const") {
        if value != c {
            fail(format!("{value} is not {c}"));
        }
    }
    if let Some(options) = schema.get("enum").and_then(Value::as_array) {
        if !options.contains(value) {
            fail(format!("{value} is not one of {options:?}"));
        }
    }
    if let Some(t) = schema.get("type").and_then(Value::as_str) {
        let ok = match t {
            "object" => value.is_object(),
            "array" => value.is_array(),
            "string" => value.is_string(),
            "integer" => value.is_i64() || value.is_u64(),
            "boolean" => value.is_boolean(),
            other => panic!("the validator does not know type {other}"),
        };
        if !ok {
            fail(format!("{value} is not of type {t}"));
            return;
        }
    }
    if let Some(n) = value.as_f64().filter(|_| value.is_number()) {
        if schema
            .get("minimum")
            .and_then(Value::as_f64)
            .is_some_and(|m| n < m)
        {
            fail(format!("{n} is below the minimum {}", schema["minimum"]));
        }
        if schema
            .get("maximum")
            .and_then(Value::as_f64)
            .is_some_and(|m| n > m)
        {
            fail(format!("{n} is above the maximum {}", schema["maximum"]));
        }
    }
    if let Some(s) = value.as_str() {
        if schema
            .get("maxLength")
            .and_then(Value::as_u64)
            .is_some_and(|m| s.len() as u64 > m)
        {
            fail(format!("{s:?} is longer than {}", schema["maxLength"]));
        }
        if schema
            .get("minLength")
            .and_then(Value::as_u64)
            .is_some_and(|m| (s.len() as u64) < m)
        {
            fail(format!("{s:?} is shorter than {}", schema["minLength"]));
        }
        if let Some(format) = schema.get("format").and_then(Value::as_str) {
            if !has_format(s, format) {
                fail(format!("{s:?} is not a {format}"));
            }
        }
    }
    if let Some(items) = value.as_array() {
        if schema
            .get("minItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| (items.len() as u64) < m)
        {
            fail(format!("fewer than {} items", schema["minItems"]));
        }
        if let Some(item) = schema.get("items") {
            for (i, v) in items.iter().enumerate() {
                validate(item, v, &format!("{path}[{i}]"), errors);
            }
        }
    }
    if let Some(object) = value.as_object() {
        for field in schema
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let field = field.as_str().expect("required names are strings");
            if !object.contains_key(field) {
                errors.push(format!("{path}: the required field {field:?} is missing"));
            }
        }
        let properties = schema.get("properties").and_then(Value::as_object);
        for (key, v) in object {
            let child = format!("{path}.{key}");
            match (
                properties.and_then(|p| p.get(key)),
                schema.get("additionalProperties"),
            ) {
                (Some(s), _) => validate(s, v, &child, errors),
                (None, Some(Value::Bool(false))) => errors.push(format!("{child}: unknown field")),
                (None, Some(s)) if s.is_object() => validate(s, v, &child, errors),
                (None, _) => {}
            }
        }
    }
}

/// The string formats of the schema (Kubernetes' validation rules).
fn has_format(s: &str, format: &str) -> bool {
    let label = |l: &str| {
        !l.is_empty()
            && l.len() <= 63
            && l.bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
            && !l.starts_with('-')
            && !l.ends_with('-')
    };
    match format {
        "dns-label" => label(s),
        "dns-subdomain" => s.len() <= 253 && s.split('.').all(label),
        "absolute-path" => s.starts_with('/'),
        // A CPU or memory quantity: digits with an optional decimal part and suffix.
        "quantity" => {
            let digits = s.trim_end_matches(|c: char| c.is_ascii_alphabetic());
            !digits.is_empty()
                && digits.bytes().all(|b| b.is_ascii_digit() || b == b'.')
                && ["", "m", "k", "M", "G", "Ki", "Mi", "Gi"].contains(&&s[digits.len()..])
        }
        other => panic!("the validator does not know format {other}"),
    }
}

/// The violations of the Indexed Job schema in `manifest`.
fn violations(manifest: &Value) -> Vec<String> {
    let mut errors = Vec::new();
    validate(&schema(), manifest, "$", &mut errors);
    errors
}

fn sweep(jobs: usize) -> Sweep {
    let info = SweepInfo {
        format: SWEEP_FORMAT.into(),
        name: "Zsolnai_Large_Step".into(),
        cwd: "/work/chainlight".into(),
        threads: 8,
        collect: None,
        runner: "target/release/chainlight".into(),
    };
    let jobs = (0..jobs)
        .map(|i| Job {
            id: format!("cornell/seed{i}"),
            argv: vec!["true".into()],
            out: None,
        })
        .collect();
    Sweep::new("/work/chainlight/out/jobs", info, jobs).unwrap()
}

#[test]
fn the_manifest_is_a_valid_indexed_job() {
    let options = K8sOptions {
        claim: Some("chainlight-work".into()),
        parallelism: 16,
        ..K8sOptions::new("registry.example.org/chainlight:2025-01")
    };
    let m = k8s_manifest(&sweep(6), &options).unwrap();
    assert_eq!(violations(&m), Vec::<String>::new(), "{m:#}");
    let spec = &m["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    assert_eq!(
        (spec["completions"].as_u64(), spec["parallelism"].as_u64()),
        (Some(6), Some(6))
    );
    let container = &spec["template"]["spec"]["containers"][0];
    assert_eq!(
        container["image"],
        "registry.example.org/chainlight:2025-01"
    );
    let command: Vec<&str> = container["command"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    // The index comes from JOB_COMPLETION_INDEX, which the Job controller sets in every pod.
    assert_eq!(
        command,
        [
            "target/release/chainlight",
            "sweep",
            "task",
            "out/jobs",
            "--workdir",
            "/work/chainlight"
        ]
    );
    assert_eq!(container["resources"]["requests"]["cpu"], "8");
    assert_eq!(
        container["volumeMounts"][0]["mountPath"],
        "/work/chainlight"
    );
    // Without a claim the manifest is valid too (the image holds the checkout).
    let plain = k8s_manifest(&sweep(1), &K8sOptions::new("chainlight:latest")).unwrap();
    assert_eq!(violations(&plain), Vec::<String>::new(), "{plain:#}");
}

#[test]
fn broken_manifests_fail_the_schema() {
    let good = k8s_manifest(&sweep(4), &K8sOptions::new("chainlight:latest")).unwrap();
    assert!(violations(&good).is_empty());
    let broken = |edit: &dyn Fn(&mut Value), needle: &str| {
        let mut m = good.clone();
        edit(&mut m);
        let v = violations(&m);
        assert!(
            v.iter().any(|e| e.contains(needle)),
            "expected {needle:?} in {v:?}"
        );
    };
    broken(
        &|m| drop(m["spec"].as_object_mut().unwrap().remove("completionMode")),
        "\"completionMode\" is missing",
    );
    broken(
        &|m| m["spec"]["completionMode"] = json!("NonIndexed"),
        "completionMode",
    );
    broken(
        &|m| m["spec"]["completions"] = json!("4"),
        "$.spec.completions: \"4\" is not of type integer",
    );
    broken(
        &|m| m["spec"]["parallelism"] = json!(1.5),
        "is not of type integer",
    );
    broken(
        &|m| m["spec"]["completions"] = json!(100_001),
        "above the maximum",
    );
    broken(
        &|m| m["spec"]["template"]["spec"]["restartPolicy"] = json!("Always"),
        "restartPolicy",
    );
    broken(
        &|m| m["spec"]["completionsMode"] = json!("Indexed"),
        "$.spec.completionsMode: unknown field",
    );
    broken(
        &|m| m["metadata"]["name"] = json!("Chainlight_Sweep"),
        "is not a dns-label",
    );
    broken(&|m| m["apiVersion"] = json!("batch/v1beta1"), "apiVersion");
    broken(
        &|m| m["spec"]["template"]["spec"]["containers"] = json!([]),
        "fewer than 1 items",
    );
    broken(
        &|m| {
            drop(
                m["spec"]["template"]["spec"]["containers"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("image"),
            )
        },
        "\"image\" is missing",
    );
    broken(
        &|m| {
            m["spec"]["template"]["spec"]["containers"][0]["resources"]["requests"]["cpu"] =
                json!(8)
        },
        "is not of type string",
    );
}

#[test]
fn bad_options_are_refused_naming_the_flag() {
    let s = sweep(2);
    for (options, needle) in [
        (K8sOptions::new(""), "--image"),
        (K8sOptions::new("a b"), "--image"),
        (
            K8sOptions {
                parallelism: 0,
                ..K8sOptions::new("x")
            },
            "--parallelism",
        ),
        (
            K8sOptions {
                claim: Some("Bad_Claim".into()),
                ..K8sOptions::new("x")
            },
            "--claim",
        ),
    ] {
        let e = k8s_manifest(&s, &options).unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }
}
