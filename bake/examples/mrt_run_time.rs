//! Modular radiance transfer's level bake and CPU evaluator (Loos et al. 2011, §6.3, §7.3;
//! the paper's Table 3 and Fig. 10) on the generated levels, for docs/BENCHMARKS.md: per level
//! its blocks, samples, level bake time (T_b->r and the solved feedback) and the CPU
//! evaluator's time for one frame's transfer (steps 2-5 on one thread, every bounce and the
//! first only), median of 5. One dictionary at the `mrt` method's defaults but 4,096 rays.
//!
//!     cargo run --release -p relume-bake --example mrt_run_time

use glam::Vec3;
use relume_bake::gltf_load;
use relume_bake::mrt::baker::bake_level;
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::{BlockSettings, InterfaceSettings};
use std::path::Path;
use std::time::Instant;

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let block = BlockSettings { gather_rays: 4096, ..BlockSettings::default() };
    let lightfield = InterfaceSettings { positions: 8, directions: 12, supersamples: 2, gather_rays: 1024, ..InterfaceSettings::default() };
    let clock = Instant::now();
    let dictionary = Dictionary::build(&block, &lightfield, |_| Ok(())).expect("the dictionary builds");
    println!("dictionary: {:.1} s", clock.elapsed().as_secs_f64());
    println!("| level | blocks | samples | level bake | CPU transfer, every bounce | first bounce only |");
    println!("|---|---|---|---|---|---|");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for name in ["mrt-cube", "mrt-corridor", "mrt-maze", "mrt-maze-large"] {
        let scene = gltf_load::load(&root.join(format!("{name}.gltf"))).expect("a shipped scene").scene;
        let clock = Instant::now();
        let (_, level) = bake_level(&scene, &dictionary, 8).expect("the level bakes");
        let baked = clock.elapsed().as_secs_f64();
        let direct: Vec<Vec3> = level.samples.iter().map(|s| Vec3::splat(1.0 / (1.0 + s.position.length_squared()))).collect();
        let time = |feedback: bool| {
            median(
                (0..5)
                    .map(|_| {
                        let clock = Instant::now();
                        std::hint::black_box(level.indirect(&dictionary, &direct, feedback));
                        clock.elapsed().as_secs_f64() * 1e3
                    })
                    .collect(),
            )
        };
        println!(
            "| {name} | {} | {} | {baked:.2} s | {:.1} ms | {:.1} ms |",
            level.blocks.len(),
            level.samples.len(),
            time(true),
            time(false)
        );
    }
}
