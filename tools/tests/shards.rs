//! Bakes split into shards (docs/CLUSTER.md): every method's merged artifact is the whole
//! bake's bytes at 1, 3 and 7 shards run through a one-node Slurm cluster on loopback
//! (tools/slurm-local.sh); a shard killed mid-way is retried alone and the merge is still the
//! same bytes; a merge refuses a part that is missing, from another plan or damaged, naming it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-shards-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs relume in `dir`; panics with its output unless it succeeds.
fn relume(dir: &Path, args: &[&str]) -> String {
    let output = run(dir, args);
    assert!(output.status.success(), "relume {}: {}", args.join(" "), String::from_utf8_lossy(&output.stderr));
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_relume")).current_dir(dir).args(args).output().expect("run relume")
}

/// A bake of each method small enough for a test: the method's scene and flags.
fn bakes(dir: &Path) -> Vec<(&'static str, Vec<String>)> {
    let scene = |name: &str| repo().join("scenes").join(name).display().to_string();
    let cache = dir.join("dictionaries").display().to_string();
    let with =
        |name: &str, flags: &[&str]| -> Vec<String> { std::iter::once(scene(name)).chain(flags.iter().map(|f| f.to_string())).collect() };
    vec![
        ("obscurance", with("cornell.gltf", &["--method", "obscurance", "--rays", "32", "--patches", "6000"])),
        (
            "light-path-maps",
            with("cornell.gltf", &["--method", "light-path-maps", "--rays", "16", "--patches", "3000", "--entry-points", "128"]),
        ),
        ("light-cloud", with("cornell-cloud.gltf", &["--method", "light-cloud", "--samples", "4"])),
        ("fiv", with("fiv-blobs.gltf", &["--method", "fiv", "--grid", "32x17x15"])),
        (
            "mrt",
            with("mrt-cube.gltf", &["--method", "mrt", "--gather-rays", "64", "--samples-per-face", "8", "--dictionary-cache", &cache]),
        ),
    ]
}

/// Panics unless the artifact folders `a` and `b` hold the same files with the same bytes,
/// but for stats.json (timings).
fn assert_same_artifact(a: &Path, b: &Path) {
    let names = |dir: &Path| -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n != "stats.json")
            .collect();
        names.sort();
        names
    };
    assert_eq!(names(a), names(b), "{} and {}", a.display(), b.display());
    for name in names(a) {
        let same = std::fs::read(a.join(&name)).expect("read") == std::fs::read(b.join(&name)).expect("read");
        assert!(same, "{name} differs between {} and {}", a.display(), b.display());
    }
}

/// One local cluster at a time: each starts its own, on free ports.
static ONE_CLUSTER: Mutex<()> = Mutex::new(());

/// A one-node Slurm cluster under a folder of its own, stopped (exactly what it started) when
/// dropped, also when a test fails.
struct Cluster {
    dir: PathBuf,
    conf: String,
}

impl Cluster {
    fn start(name: &str) -> Cluster {
        let dir = temp_dir(name);
        let started = Command::new("bash").arg(repo().join("tools/slurm-local.sh")).arg("start").arg(&dir).output().expect("run bash");
        // Constructed before the check, so a half-started cluster is stopped too.
        let env = std::fs::read_to_string(dir.join("env")).unwrap_or_default();
        let conf = env.trim().trim_start_matches("export SLURM_CONF=").to_string();
        let cluster = Cluster { dir, conf };
        assert!(
            started.status.success(),
            "the local Slurm cluster did not start (tools/setup.sh installs slurmctld, slurmd, slurm-client and munge): {}",
            String::from_utf8_lossy(&started.stderr)
        );
        cluster
    }

    /// Runs the plan's submit.sh and waits for its merge; `relume` stands in for the program.
    fn submit(&self, plan: &Path, relume: &Path) -> String {
        let output = self.submitted(plan, relume);
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        assert!(output.status.success(), "submit.sh: {stdout}{}", String::from_utf8_lossy(&output.stderr));
        stdout
    }

    /// Waits until no job is queued or running (at most two minutes).
    fn wait_idle(&self) {
        for _ in 0..600 {
            let queue = Command::new("squeue").arg("--noheader").env("SLURM_CONF", &self.conf).output().expect("run squeue");
            if queue.status.success() && queue.stdout.is_empty() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(200));
        }
        panic!("the local cluster's jobs did not end within two minutes");
    }

    /// As `submit`, whatever the outcome (sbatch --wait on a merge cancelled because a shard
    /// failed returns 0 or not, as Slurm has it).
    fn submitted(&self, plan: &Path, relume: &Path) -> Output {
        Command::new("bash")
            .arg(plan.join("slurm/submit.sh"))
            .arg("--wait")
            .env("SLURM_CONF", &self.conf)
            .env("RELUME", relume)
            .output()
            .expect("run submit.sh")
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash").arg(repo().join("tools/slurm-local.sh")).arg("stop").arg(&self.dir).status();
    }
}

/// Plans `bake` in `shards` shards with the Slurm scripts, the artifact to `artifact`.
fn plan(dir: &Path, bake: &[String], shards: usize, plan: &Path, artifact: &Path) {
    let mut args: Vec<&str> = vec!["bake", "plan"];
    args.extend(bake.iter().map(String::as_str));
    let shards = shards.to_string();
    let (plan, artifact) = (plan.display().to_string(), artifact.display().to_string());
    args.extend(["--shards", &shards, "--out", &plan, "--slurm", "--artifact", &artifact, "--threads", "2"]);
    relume(dir, &args);
}

fn whole(dir: &Path, bake: &[String], out: &Path) {
    let mut args: Vec<&str> = vec!["bake"];
    args.extend(bake.iter().map(String::as_str));
    args.extend(["--out", out.to_str().expect("a UTF-8 path"), "--threads", "2"]);
    relume(dir, &args);
}

#[test]
fn every_methods_merged_shards_are_the_whole_bakes_bytes_through_slurm() {
    let _one = ONE_CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let dir = temp_dir("every-method");
    let cluster = Cluster::start("every-method-slurm");
    for (method, bake) in bakes(&dir) {
        let one = dir.join(format!("{method}-whole"));
        whole(&dir, &bake, &one);
        for shards in [1, 3, 7] {
            let (folder, merged) = (dir.join(format!("{method}-plan-{shards}")), dir.join(format!("{method}-{shards}")));
            plan(&dir, &bake, shards, &folder, &merged);
            cluster.submit(&folder, Path::new(env!("CARGO_BIN_EXE_relume")));
            assert_same_artifact(&one, &merged);
        }
    }
}

/// A stand-in for relume that kills shard 1's first run once it has begun writing its part.
fn killing_wrapper(dir: &Path) -> PathBuf {
    let path = dir.join("kill-shard-1.sh");
    let script = format!(
        r#"#!/bin/bash
if [ "$1 $2" = "bake shard" ] && [ "$SLURM_ARRAY_TASK_ID" = 1 ] && [ ! -e "{mark}" ]; then
  touch "{mark}"
  "{relume}" "$@" & pid=$!
  until compgen -G "$3/parts/.part-1-*.tmp" > /dev/null; do
    kill -0 $pid 2> /dev/null || exit 99
    sleep 0.01
  done
  kill -KILL $pid
  wait $pid
  exit
fi
exec "{relume}" "$@"
"#,
        mark = dir.join("killed").display(),
        relume = env!("CARGO_BIN_EXE_relume")
    );
    std::fs::write(&path, script).expect("write the wrapper");
    std::fs::set_permissions(&path, std::os::unix::fs::PermissionsExt::from_mode(0o755)).expect("make the wrapper a program");
    path
}

#[test]
fn a_shard_killed_mid_way_is_retried_alone_and_the_merge_is_the_same_bytes() {
    let _one = ONE_CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let dir = temp_dir("killed");
    let cluster = Cluster::start("killed-slurm");
    let bake: Vec<String> = vec![
        repo().join("scenes/cornell-cloud.gltf").display().to_string(),
        "--method".into(),
        "light-cloud".into(),
        "--samples".into(),
        "16".into(),
    ];
    let (folder, merged, one) = (dir.join("plan"), dir.join("merged"), dir.join("whole"));
    whole(&dir, &bake, &one);
    plan(&dir, &bake, 3, &folder, &merged);
    let first = cluster.submitted(&folder, &killing_wrapper(&dir));
    let first = format!("{}{}", String::from_utf8_lossy(&first.stdout), String::from_utf8_lossy(&first.stderr));
    assert!(first.contains("submitted shards 0,1,2 as job"), "{first}");
    assert!(dir.join("killed").exists(), "the wrapper never ran shard 1");
    // The merge is cancelled as soon as shard 1 fails; shard 2 may still be running.
    cluster.wait_idle();
    assert!(!merged.exists(), "the merge ran after a failed shard");
    let missing = relume(&dir, &["bake", "status", folder.to_str().expect("UTF-8"), "--missing"]);
    assert_eq!(missing.trim(), "1", "only the killed shard is missing");
    let again = cluster.submit(&folder, Path::new(env!("CARGO_BIN_EXE_relume")));
    assert!(again.contains("submitted shards 1 as job"), "{again}");
    assert_same_artifact(&one, &merged);
}

/// Shards run one by one, without Slurm, of a small obscurance bake into `folder`.
fn baked_parts(dir: &Path, folder: &Path, shards: usize) -> Vec<String> {
    let bake = &bakes(dir)[0].1;
    let mut args: Vec<&str> = vec!["bake", "plan"];
    args.extend(bake.iter().map(String::as_str));
    let (count, path) = (shards.to_string(), folder.display().to_string());
    args.extend(["--shards", &count, "--out", &path]);
    relume(dir, &args);
    (0..shards).map(|i| relume(dir, &["bake", "shard", &path, "--index", &i.to_string()])).collect()
}

fn refused_merge(dir: &Path, folder: &Path) -> String {
    let output = run(dir, &["bake", "merge", folder.to_str().expect("UTF-8"), "--out", dir.join("refused").to_str().expect("UTF-8")]);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(!dir.join("refused").exists(), "a refused merge wrote its artifact");
    stderr
}

#[test]
fn a_merge_refuses_a_part_missing_from_another_plan_or_damaged_naming_it() {
    let dir = temp_dir("refusals");
    let (folder, other) = (dir.join("plan"), dir.join("other"));
    baked_parts(&dir, &folder, 3);
    let rerun = relume(&dir, &["bake", "shard", folder.to_str().expect("UTF-8"), "--index", "1"]);
    assert!(rerun.contains("shard 1: its part is complete, kept"), "{rerun}");

    let part = |plan: &Path, file: &str| plan.join("parts").join(file);
    let rows = part(&folder, "part-2-0.rows");
    let mut bytes = std::fs::read(&rows).expect("read the rows");
    bytes[100] ^= 1;
    std::fs::write(&rows, &bytes).expect("damage the rows");
    let damaged = refused_merge(&dir, &folder);
    assert!(damaged.contains("part-2-0.rows") && damaged.contains("damaged"), "{damaged}");
    bytes[100] ^= 1;
    std::fs::write(&rows, &bytes).expect("mend the rows");

    // A plan of the same bake in 4 shards: its part 0 is not this plan's.
    baked_parts(&dir, &other, 4);
    for name in ["part-0.json", "part-0-0.rows"] {
        std::fs::copy(part(&other, name), part(&folder, name)).expect("copy a foreign part");
    }
    let foreign = refused_merge(&dir, &folder);
    assert!(foreign.contains("part-0.json") && foreign.contains("belongs to another plan"), "{foreign}");

    std::fs::remove_file(part(&folder, "part-0.json")).expect("remove a part");
    let missing = refused_merge(&dir, &folder);
    assert!(missing.contains("part-0.json") && missing.contains("part 0 is missing"), "{missing}");
    assert!(missing.contains("--index 0"), "the fix names the shard to rerun: {missing}");
}

/// A plan refuses what cannot be split the same way twice, and impossible splits.
#[test]
fn a_plan_refuses_a_time_limit_and_more_shards_than_items() {
    let dir = temp_dir("plan-refusals");
    let scene = repo().join("scenes/cornell.gltf").display().to_string();
    let out = dir.join("plan").display().to_string();
    let plan = |extra: &[&str]| {
        let mut args = vec!["bake", "plan", &scene, "--method", "obscurance", "--rays", "1", "--patches", "200", "--out", &out];
        args.extend(extra);
        let output = run(&dir, &args);
        assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stderr));
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    assert!(plan(&["--shards", "2", "--time-limit", "60"]).contains("--time-limit"));
    assert!(plan(&["--shards", "100000"]).contains("--shards: 100000 shards of"));
    assert!(!dir.join("plan").exists(), "a refused plan wrote its folder");
}
