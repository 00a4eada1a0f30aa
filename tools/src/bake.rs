//! `relume bake`: precompute a method's data for a scene into a bake artifact folder
//! (format: docs/FORMATS.md). Methods: obscurance (Iones et al. 2003), with its
//! ambient-occlusion and spectral (Umenhoffer et al. §3.3) variants; light path maps
//! (Umenhoffer et al. §3.2): the spectral obscurance plus entry points, transfers and their
//! clustered PCA.

use super::*;
use relume_bake::artifact::{BakeOutput, PageLayout};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::light_path_maps::{self as lpm, Compressed, Compression, LightPathMapSettings};
use relume_bake::obscurance::{bake_obscurance, ObscuranceMap, ObscuranceSettings, Variant};
use relume_bake::settings::{LightRegion, LightingSettings};
use relume_bake::work::{peak_memory_bytes, reset_peak_memory};
use serde_json::{json, Value};

#[derive(Args)]
pub(crate) struct BakeArgs {
    /// A glTF 2.0 scene (.gltf or .glb).
    scene: PathBuf,
    /// The method to bake.
    #[arg(long, value_parser = ["obscurance", "light-path-maps"])]
    method: String,
    /// obscurance (001 eq. 2-3), ao (rho a step at L_max) or spectral (000 §3.3); default
    /// obscurance, spectral for light-path-maps (000's small-scale term).
    #[arg(long)]
    variant: Option<String>,
    /// Light path maps: entry points wanted (E).
    #[arg(long, default_value_t = 4096)]
    entry_points: u32,
    /// Light path maps: test points sampling the scene's light region box (M; default the scene's).
    #[arg(long)]
    test_points: Option<u32>,
    /// Light path maps: random walks per entry point.
    #[arg(long, default_value_t = 1)]
    walks: u32,
    /// Light path maps: connections shorter than this are dropped, metres (default: L_max).
    #[arg(long)]
    threshold: Option<f32>,
    /// Light path maps: clusters C (with --basis; default: chosen by --error-budget).
    #[arg(long, requires = "basis", conflicts_with_all = ["error_budget", "uncompressed"])]
    clusters: Option<usize>,
    /// Light path maps: eigen-textures per cluster D.
    #[arg(long, requires = "clusters")]
    basis: Option<usize>,
    /// Light path maps: the smallest C and D whose relative error of the transfers is within this.
    #[arg(long, default_value_t = 0.1, conflicts_with = "uncompressed")]
    error_budget: f64,
    /// Light path maps: keep every transfer (one cluster per entry point, no PCA).
    #[arg(long)]
    uncompressed: bool,
    /// tau of rho(L) = 1 - exp(-L / tau), metres (default: the scene's).
    #[arg(long)]
    tau: Option<f32>,
    /// L_max, metres (default: the scene's).
    #[arg(long)]
    l_max: Option<f32>,
    /// Rays per texel, spread over the texel's patch.
    #[arg(long, default_value_t = 256)]
    rays: u32,
    /// Lightmap texels per metre (default: the scene's).
    #[arg(long, conflicts_with = "patches")]
    texel_density: Option<f32>,
    /// Aim for this many covered texels (patches) instead of a texel density.
    #[arg(long)]
    patches: Option<u32>,
    /// Empty texels between charts.
    #[arg(long, default_value_t = 2)]
    gutter: u32,
    /// Largest atlas page side in texels; more pages when the charts do not fit one.
    #[arg(long, default_value_t = 4096)]
    atlas_max: u32,
    /// Largest angle between faces of one chart, degrees.
    #[arg(long, default_value_t = 60.0)]
    discontinuity_angle: f32,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Stop tracing after this many seconds, at a whole pass of 32 rays per texel.
    #[arg(long)]
    time_limit: Option<f64>,
    /// The artifact folder (default: out/<scene>/<method>).
    #[arg(long, short)]
    out: Option<PathBuf>,
}

/// One stage's cost, as stats.json records it.
struct Stage {
    name: &'static str,
    seconds: f64,
    peak_memory_bytes: Option<u64>,
}

fn timed<R>(name: &'static str, stages: &mut Vec<Stage>, work: impl FnOnce() -> R) -> R {
    reset_peak_memory();
    let start = Instant::now();
    let result = work();
    stages.push(Stage { name, seconds: start.elapsed().as_secs_f64(), peak_memory_bytes: peak_memory_bytes() });
    result
}

/// The artifact folder `relume bake` writes for a scene and method when no --out is given.
pub(crate) fn default_bake_dir(scene: &Path, method: &str) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
    PathBuf::from("out").join(stem).join(method)
}

impl BakeArgs {
    /// `relume bake SCENE --method obscurance` with every other flag at its default.
    pub(crate) fn obscurance(scene: &Path, rays: u32) -> BakeArgs {
        BakeArgs {
            scene: scene.to_path_buf(),
            method: "obscurance".into(),
            variant: None,
            entry_points: 4096,
            test_points: None,
            walks: 1,
            threshold: None,
            clusters: None,
            basis: None,
            error_budget: 0.1,
            uncompressed: false,
            tau: None,
            l_max: None,
            rays,
            texel_density: None,
            patches: None,
            gutter: 2,
            atlas_max: 4096,
            discontinuity_angle: 60.0,
            seed: 0,
            threads: None,
            time_limit: None,
            out: None,
        }
    }

    /// `relume bake SCENE --method METHOD FLAGS..`, parsed as the command line would be.
    pub(crate) fn from_flags(scene: &Path, method: &str, flags: &[String]) -> Result<BakeArgs> {
        #[derive(clap::Parser)]
        struct Bake {
            #[command(flatten)]
            args: BakeArgs,
        }
        let argv =
            ["bake".to_string(), scene.display().to_string(), "--method".into(), method.into()].into_iter().chain(flags.iter().cloned());
        let bake = <Bake as clap::Parser>::try_parse_from(argv).map_err(|e| {
            let text = e.render().to_string();
            anyhow::anyhow!("bake flags {}: {}", flags.join(" "), text.lines().next().unwrap_or("").trim_start_matches("error: "))
        })?;
        Ok(bake.args)
    }

    /// `relume bake SCENE --method light-path-maps --clusters 32 --basis 2` (the sizes of 000 §3.2.3),
    /// every other flag at its default.
    pub(crate) fn light_path_maps(scene: &Path, rays: u32) -> BakeArgs {
        BakeArgs { method: "light-path-maps".into(), clusters: Some(32), basis: Some(2), ..BakeArgs::obscurance(scene, rays) }
    }
}

pub(crate) fn bake_command(args: &BakeArgs) -> Result<()> {
    let loaded = load_with_camera(&args.scene, None)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    let out = args.out.clone().unwrap_or_else(|| default_bake_dir(&args.scene, &args.method));
    let summary = bake_scene(&loaded.scene, args, &out)?;
    print!("{summary}");
    Ok(())
}

/// Bakes `scene` as `args` say into the artifact folder `out`; returns a summary to print.
pub(crate) fn bake_scene(scene: &Scene, args: &BakeArgs, out: &Path) -> Result<String> {
    let lighting = lighting_settings(&scene.settings, args)?;
    let atlas_settings = AtlasSettings {
        texel_density: lighting.texel_density,
        gutter: args.gutter,
        max_size: args.atlas_max,
        discontinuity_angle: args.discontinuity_angle.to_radians(),
    };
    atlas_settings.validate().map_err(|e| anyhow::anyhow!("{e} (--texel-density, --gutter, --atlas-max, --discontinuity-angle)"))?;
    let obscurance = obscurance_settings(&lighting, args)?;
    obscurance.validate().map_err(|e| anyhow::anyhow!("{e} (--tau, --l-max, --rays, --threads)"))?;

    let mut stages = Vec::new();
    let atlas = timed("atlas", &mut stages, || match args.patches {
        Some(0) => Err(anyhow::anyhow!("--patches 0: ask for at least one patch")),
        Some(patches) => Ok(Atlas::build_for_patch_count(scene, &atlas_settings, patches)?),
        None => Ok(Atlas::build(scene, &atlas_settings)?),
    })?;
    let bvh = timed("bvh", &mut stages, || SceneBvh::new(scene));
    let map = timed("obscurance", &mut stages, || bake_obscurance(scene, &bvh, &atlas, &obscurance)).map_err(anyhow::Error::msg)?;
    let layout = PageLayout { width: atlas.width, height: atlas.height, pages: atlas.pages };
    let transfer = match args.method.as_str() {
        "light-path-maps" => Some(bake_light_path_maps(scene, &bvh, &atlas, &lighting, args, &mut stages)?),
        _ => None,
    };
    let mut parameters = parameters(&obscurance, &atlas_settings, args);
    let mut stats = stats(&stages, &map, &obscurance);
    if let Some((_, facts)) = &transfer {
        parameters["light_path_maps"] = facts["parameters"].clone();
        stats["light_path_maps"] = facts["stats"].clone();
    }

    let output = BakeOutput {
        method: &args.method,
        scene,
        parameters,
        atlas_summary: atlas_summary(&atlas, &atlas_settings),
        layout,
        meshes: &atlas.meshes,
        texels: &atlas.texels,
        lightmap: &map.values,
        transfer: transfer.as_ref().map(|(c, _)| &c.transfer),
        stats,
    };
    output.write(out)?;
    let mut text = summary(&atlas, &map, &stages, out);
    if let Some((_, facts)) = &transfer {
        text.insert_str(
            text.rfind("wrote").unwrap_or(text.len()),
            &format!("light path maps: {}\n", facts["summary"].as_str().unwrap_or("")),
        );
    }
    Ok(text)
}

/// Entry points, transfers and their compression (000 §3.2), each a timed stage; returns the
/// compressed transfer and its parameters, statistics and a one-line summary.
fn bake_light_path_maps(
    scene: &Scene,
    bvh: &SceneBvh,
    atlas: &Atlas,
    lighting: &LightingSettings,
    args: &BakeArgs,
    stages: &mut Vec<Stage>,
) -> Result<(Compressed, Value)> {
    let settings = LightPathMapSettings {
        entry_points: args.entry_points,
        walks: args.walks,
        threshold: args.threshold.unwrap_or(lighting.l_max),
        max_depth: 64,
        seed: args.seed,
        threads: args.threads,
        time_limit: time_limit(args)?,
        progress: true,
    };
    settings.validate().map_err(|e| anyhow::anyhow!("{e} (--entry-points, --walks, --threshold, --threads)"))?;
    let region = match (&lighting.light_region, args.test_points) {
        (Some(LightRegion::Box { min, max, .. }), Some(m)) => Some(LightRegion::Box { min: *min, max: *max, test_points: m }),
        (_, Some(_)) => bail!("--test-points needs a scene whose extras.relume.light_path_maps.region is a box"),
        (region, None) => region.clone(),
    };
    if let Some(r) = &region {
        r.validate().map_err(|e| anyhow::anyhow!("{e} (--test-points)"))?;
    }
    let compression = match (args.uncompressed, args.clusters, args.basis) {
        (true, _, _) => Compression::None,
        (false, Some(clusters), Some(basis)) if clusters >= 1 => Compression::Fixed { clusters, basis },
        (false, Some(_), _) => bail!("--clusters must be at least 1"),
        _ if args.error_budget.is_finite() && args.error_budget >= 0.0 => Compression::Budget(args.error_budget),
        _ => bail!("--error-budget {} must be a finite relative error >= 0", args.error_budget),
    };
    let entries = timed("entry_points", stages, || {
        let tests = lpm::test_points(scene, region.as_ref(), args.seed)?;
        lpm::entry_points(scene, bvh, tests, settings.entry_points, args.seed)
    })
    .map_err(anyhow::Error::msg)?;
    let transfers =
        timed("transfer", stages, || lpm::bake_transfers(scene, bvh, atlas, &entries.entries, &settings)).map_err(anyhow::Error::msg)?;
    let compressed =
        timed("cpca", stages, || lpm::compress(&transfers, &entries.entries, atlas.texels.len(), lighting.light_area, compression))
            .map_err(anyhow::Error::msg)?;
    let uncompressed_bytes = transfers.values.len() * 12;
    let summary = format!(
        "{} entry points from {} test points, {} texels, {} virtual lights, {} connections; C = {}, D = {}, relative error {:.4}, {:.1} MiB -> {:.1} MiB",
        entries.entries.len(),
        entries.test_points.len(),
        transfers.texels.len(),
        transfers.virtual_lights,
        transfers.connections,
        compressed.clusters,
        compressed.basis,
        compressed.relative_error,
        uncompressed_bytes as f64 / (1 << 20) as f64,
        compressed.transfer.size_bytes() as f64 / (1 << 20) as f64,
    );
    let facts = json!({
        "parameters": {
            "entry_points": settings.entry_points,
            "test_points": entries.test_points.len(),
            "walks": settings.walks,
            "threshold": short(settings.threshold),
            "compression": format!("{compression:?}"),
            "seed": settings.seed,
        },
        "stats": {
            "entry_points": entries.entries.len(),
            "rays_per_test_point": entries.rays_per_test_point,
            "covered_texels": transfers.texels.len(),
            "walks": transfers.walks,
            "virtual_lights": transfers.virtual_lights,
            "connections": transfers.connections,
            "clusters": compressed.clusters,
            "basis": compressed.basis,
            "relative_error": compressed.relative_error,
            "uncompressed_bytes": uncompressed_bytes,
            "compressed_bytes": compressed.transfer.size_bytes(),
        },
        "summary": summary,
    });
    Ok((compressed, facts))
}

fn lighting_settings(scene: &LightingSettings, args: &BakeArgs) -> Result<LightingSettings> {
    let s = LightingSettings {
        tau: args.tau.unwrap_or(scene.tau),
        l_max: args.l_max.unwrap_or(scene.l_max),
        texel_density: args.texel_density.unwrap_or(scene.texel_density),
        ..scene.clone()
    };
    s.validate().map_err(|e| anyhow::anyhow!("{e} (--tau, --l-max, --texel-density or the scene's extras.relume)"))?;
    Ok(s)
}

fn time_limit(args: &BakeArgs) -> Result<Option<Duration>> {
    match args.time_limit {
        Some(s) if !(s.is_finite() && s > 0.0) => bail!("--time-limit {s}: give a positive number of seconds"),
        s => Ok(s.map(Duration::from_secs_f64)),
    }
}

fn obscurance_settings(lighting: &LightingSettings, args: &BakeArgs) -> Result<ObscuranceSettings> {
    let default = if args.method == "light-path-maps" { "spectral" } else { "obscurance" };
    let name = args.variant.as_deref().unwrap_or(default);
    let Some(variant) = Variant::parse(name) else {
        bail!("--variant {name}: use obscurance, ao or spectral");
    };
    let time_limit = time_limit(args)?;
    Ok(ObscuranceSettings {
        variant,
        tau: lighting.tau,
        l_max: lighting.l_max,
        rays_per_texel: args.rays,
        seed: args.seed,
        threads: args.threads,
        time_limit,
        progress: true,
    })
}

fn parameters(o: &ObscuranceSettings, a: &AtlasSettings, args: &BakeArgs) -> Value {
    json!({
        "variant": o.variant.name(),
        "tau": short(o.tau),
        "l_max": short(o.l_max),
        "rays_per_texel": o.rays_per_texel,
        "seed": o.seed,
        "texel_density": short(a.texel_density),
        "patches": args.patches,
        "gutter": a.gutter,
        "atlas_max": a.max_size,
        "discontinuity_angle_degrees": short(args.discontinuity_angle),
    })
}

/// An f32 as JSON in its shortest round-trip form (0.15, not 0.15000000596046448).
fn short(x: f32) -> Value {
    x.to_string().parse::<f64>().map_or(Value::Null, |v| json!(v))
}

fn atlas_summary(atlas: &Atlas, settings: &AtlasSettings) -> Value {
    json!({
        "width": atlas.width,
        "height": atlas.height,
        "pages": atlas.pages,
        "charts": atlas.charts.len(),
        "covered_texels": atlas.covered_texels(),
        "utilization": atlas.utilization(),
        "too_small_triangles": atlas.too_small,
        "texel_density": short(settings.texel_density),
    })
}

fn stats(stages: &[Stage], map: &ObscuranceMap, o: &ObscuranceSettings) -> Value {
    let bake_seconds = stages.iter().find(|s| s.name == "obscurance").map_or(0.0, |s| s.seconds);
    json!({
        "stages": stages.iter().map(|s| json!({ "name": s.name, "seconds": s.seconds, "peak_memory_bytes": s.peak_memory_bytes })).collect::<Vec<_>>(),
        "rays_per_texel": map.rays_per_texel,
        "rays_per_texel_asked": o.rays_per_texel,
        "rays_traced": map.rays_traced,
        "rays_per_second": map.rays_traced as f64 / bake_seconds.max(1e-9),
        "threads": o.threads.unwrap_or_else(rayon_threads),
    })
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn summary(atlas: &Atlas, map: &ObscuranceMap, stages: &[Stage], out: &Path) -> String {
    use std::fmt::Write as _;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "atlas: {} charts, {} x {} x {} page(s), {} patches, utilization {:.1}%",
        atlas.charts.len(),
        atlas.width,
        atlas.height,
        atlas.pages,
        atlas.covered_texels(),
        100.0 * atlas.utilization()
    );
    if !atlas.too_small.is_empty() {
        let _ =
            writeln!(text, "warning: {} triangle(s) too small to cover a texel measurably: {:?}", atlas.too_small.len(), atlas.too_small);
    }
    for s in stages {
        let memory = s.peak_memory_bytes.map_or("?".into(), |b| format!("{:.1} MiB", b as f64 / (1 << 20) as f64));
        let _ = writeln!(text, "  {:<11} {:>8.3} s, peak memory {memory}", s.name, s.seconds);
    }
    let rate = map.rays_traced as f64 / map.seconds.max(1e-9) / 1e6;
    let _ = writeln!(text, "{} rays per texel, {} rays in {:.3} s ({rate:.2} M rays/s)", map.rays_per_texel, map.rays_traced, map.seconds);
    let _ = writeln!(text, "wrote {}", out.display());
    text
}
