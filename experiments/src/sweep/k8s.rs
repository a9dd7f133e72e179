//! The Kubernetes Indexed Job of a sweep (`k8s-job.json`, a `batch/v1` Job with
//! `completionMode: Indexed`): the pod of completion index `i` runs job `i` of the job list
//! through `chainlight sweep task`, which reads the index from `JOB_COMPLETION_INDEX`.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::sweep::joblist::{write_atomic, Sweep};
use crate::ExperimentError;

/// The manifest's file name in a sweep directory (`kubectl apply -f` reads JSON as well as
/// YAML).
pub const K8S_FILE: &str = "k8s-job.json";
/// The longest Job name: Kubernetes labels the pods with it, and a label value holds 63
/// characters; 52 leaves room for the controller's suffixes (as CronJob's limit does).
const MAX_NAME_LEN: usize = 52;

/// Where and with what the Indexed Job runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct K8sOptions {
    /// The container image: it holds the runtime (and, without a claim, the checkout with
    /// the built binaries at the working directory).
    pub image: String,
    /// Pods running at once, 1..=the number of jobs (larger values are lowered to it).
    pub parallelism: usize,
    /// A PersistentVolumeClaim holding the shared files (the checkout or the outputs), if any.
    pub claim: Option<String>,
    /// Where the claim is mounted [default: the working directory].
    pub mount: Option<PathBuf>,
    /// The working directory in the container [default: the sweep's].
    pub workdir: Option<PathBuf>,
}

impl K8sOptions {
    /// `image`, 4 pods at a time, no claim, the sweep's working directory.
    #[must_use]
    pub fn new(image: impl Into<String>) -> Self {
        Self {
            image: image.into(),
            parallelism: 4,
            claim: None,
            mount: None,
            workdir: None,
        }
    }
}

/// The Indexed Job running `sweep`: `completions` = the number of jobs, `parallelism`, one CPU
/// per render thread requested, `restartPolicy: Never` (a failed index is retried by the Job
/// controller up to `backoffLimit` = the number of jobs in all), the command
/// `<runner> sweep task <sweep dir> --workdir <workdir>`.
///
/// # Errors
/// [`ExperimentError::Invalid`] for an empty image or one with whitespace, a parallelism of 0,
/// a claim name that is not a DNS label, or a sweep name without a letter or digit.
///
/// # Example
/// ```
/// use experiments::sweep::{k8s_manifest, Job, K8sOptions, Sweep, SweepInfo, SWEEP_FORMAT};
///
/// let info = SweepInfo {
///     format: SWEEP_FORMAT.into(),
///     name: "zsolnai_large_step".into(),
///     cwd: "/work".into(),
///     threads: 8,
///     collect: None,
///     runner: "target/release/chainlight".into(),
/// };
/// let job = |id: &str| Job { id: id.into(), argv: vec!["true".into()], out: None };
/// let sweep = Sweep::new("/work/out/jobs", info, vec![job("a"), job("b"), job("c")])?;
/// let m = k8s_manifest(&sweep, &K8sOptions::new("registry.example/chainlight:1"))?;
/// assert_eq!(m["spec"]["completionMode"], "Indexed");
/// assert_eq!((m["spec"]["completions"].as_u64(), m["spec"]["parallelism"].as_u64()), (Some(3), Some(3)));
/// assert_eq!(m["metadata"]["name"], "chainlight-zsolnai-large-step");
/// # Ok::<(), experiments::ExperimentError>(())
/// ```
pub fn k8s_manifest(sweep: &Sweep, options: &K8sOptions) -> Result<Value, ExperimentError> {
    let invalid = |m: String| Err(ExperimentError::Invalid(m));
    let image = options.image.trim();
    if image.is_empty() || image.chars().any(char::is_whitespace) {
        return invalid(format!("--image {:?} is not an image name", options.image));
    }
    if options.parallelism == 0 {
        return invalid("--parallelism must be at least 1".into());
    }
    let name = dns_label(&format!("chainlight-{}", sweep.info.name), MAX_NAME_LEN);
    let n = sweep.jobs.len();
    let workdir = options
        .workdir
        .clone()
        .unwrap_or_else(|| sweep.info.cwd.clone());
    let dir = in_workdir(&sweep.dir, &sweep.info.cwd);
    let command = [
        sweep.info.runner.clone(),
        "sweep".into(),
        "task".into(),
        dir.display().to_string(),
        "--workdir".into(),
        workdir.display().to_string(),
    ];
    let mut container = json!({
        "name": "job",
        "image": image,
        "imagePullPolicy": "IfNotPresent",
        "workingDir": workdir.display().to_string(),
        "command": command,
        "resources": { "requests": { "cpu": sweep.info.threads.max(1).to_string() } },
    });
    let mut pod = json!({ "restartPolicy": "Never", "containers": [] });
    if let Some(claim) = &options.claim {
        if dns_label(claim, 253) != *claim {
            return invalid(format!("--claim {claim:?} is not a lowercase DNS name"));
        }
        let mount = options.mount.as_ref().unwrap_or(&workdir);
        container["volumeMounts"] =
            json!([{ "name": "shared", "mountPath": mount.display().to_string() }]);
        pod["volumes"] =
            json!([{ "name": "shared", "persistentVolumeClaim": { "claimName": claim } }]);
    }
    pod["containers"] = json!([container]);
    let labels = json!({ "app.kubernetes.io/name": "chainlight-sweep", "chainlight/sweep": name });
    Ok(json!({
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": { "name": name, "labels": labels },
        "spec": {
            "completionMode": "Indexed",
            "completions": n,
            "parallelism": options.parallelism.min(n),
            "backoffLimit": n,
            "template": { "metadata": { "labels": labels }, "spec": pod },
        },
    }))
}

/// Writes `sweep.dir/k8s-job.json`, the [`k8s_manifest`] of `sweep` with `options`; returns
/// its path.
///
/// # Errors
/// As [`k8s_manifest`]; [`ExperimentError::Io`] naming the file if it cannot be written.
pub fn write_k8s_manifest(sweep: &Sweep, options: &K8sOptions) -> Result<PathBuf, ExperimentError> {
    let manifest = k8s_manifest(sweep, options)?;
    let json = serde_json::to_string_pretty(&manifest).expect("a manifest serialises");
    let path = sweep.dir.join(K8S_FILE);
    write_atomic(&path, format!("{json}\n").as_bytes())?;
    Ok(path)
}

/// `dir` relative to `cwd` when it lies inside it (so the manifest works wherever the
/// checkout is mounted), else as it is.
fn in_workdir(dir: &Path, cwd: &Path) -> PathBuf {
    dir.strip_prefix(cwd)
        .map_or_else(|_| dir.to_path_buf(), Path::to_path_buf)
}

/// `text` as a DNS label: lowercase ASCII letters, digits and `-` (every other run of
/// characters becomes one `-`), no `-` at either end, at most `max` characters.
fn dns_label(text: &str, max: usize) -> String {
    let mut label = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            label.push(c.to_ascii_lowercase());
        } else if !label.ends_with('-') {
            label.push('-');
        }
    }
    label.truncate(max);
    label.trim_matches('-').to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_dns_labels() {
        assert_eq!(
            dns_label("chainlight-Zsolnai_Large step!", 63),
            "chainlight-zsolnai-large-step"
        );
        assert_eq!(dns_label(&"a".repeat(80), 52).len(), 52);
        assert_eq!(dns_label("-x-", 63), "x");
        assert_eq!(
            in_workdir(Path::new("/w/out/jobs"), Path::new("/w")),
            PathBuf::from("out/jobs")
        );
        assert_eq!(
            in_workdir(Path::new("/scratch/jobs"), Path::new("/w")),
            PathBuf::from("/scratch/jobs")
        );
    }
}
