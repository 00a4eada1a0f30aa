//! The dictionary's block stage (Loos et al. 2011, §4 and App. A) at the paper's settings, for
//! docs/BENCHMARKS.md: per shape of the 2D dictionary, its samples, the seconds to gather F
//! and to reduce (prior, SVDs, enrichment), the prior's and M's modes for 80 / 90 / 95 % of
//! their energy (the paper's Table 2) and the worst error under uniform direct light; then, on
//! the closed cube, what App. A's enrichment trades (uniform against held-out lights).
//!
//!     cargo run --release -p relume-bake --example mrt_blocks [THREADS]

use nalgebra::DVector;
use relume_bake::mrt::block;
use relume_bake::mrt::BlockSettings;
use relume_bake::mrt::{modes_for_energy, Samples, Shape};
use relume_bake::testing::scattered_points;
use relume_bake::work::with_threads;
use std::time::Instant;

fn main() {
    let threads = std::env::args().nth(1).and_then(|t| t.parse().ok());
    let settings = BlockSettings { threads, ..BlockSettings::default() };
    println!("| open faces | n | gather F | reduce | L_d modes 80/90/95 % | M modes | uniform light, worst error |");
    println!("|---|---|---|---|---|---|---|");
    let start = Instant::now();
    for shape in Shape::dictionary() {
        let samples = Samples::new(shape, settings.samples_per_face);
        let clock = Instant::now();
        let f = with_threads(threads, || block::gather(shape, &samples, settings.gather_rays, settings.seed));
        let gathered = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let l_d = block::prior(shape, &samples, (settings.prior_grid, settings.prior_lattice), settings.light_radius);
        let ops = block::reduce(shape, samples.clone(), &f, &l_d, &settings);
        let reduced = clock.elapsed().as_secs_f64();
        let counts = |sigma: &[f64]| [0.8, 0.9, 0.95].map(|x| modes_for_energy(sigma, x).to_string()).join(" / ");
        let uniform = ops.indirect(&DVector::from_element(samples.len(), 1.0));
        let ones = f * DVector::from_element(samples.len(), 1.0);
        let worst = (uniform - ones).amax();
        println!(
            "| {} | {} | {gathered:.2} s | {reduced:.2} s | {} | {} | {worst:.4} |",
            shape.open_faces().len(),
            samples.len(),
            counts(&ops.prior_sigma),
            counts(&ops.m_sigma)
        );
    }
    println!("all six shapes: {:.1} s", start.elapsed().as_secs_f64());
    enrichment_trade(&BlockSettings { gather_rays: 4096, ..settings });
}

/// The closed cube's uniform-light error and held-out error (64 lights at least a quarter
/// side from the walls, k_self modes) for prior variants: as traced or with unit-norm columns,
/// enriched or not, a 6^3 or 8^3 lattice.
fn enrichment_trade(settings: &BlockSettings) {
    let shape = Shape::closed();
    let samples = Samples::new(shape, settings.samples_per_face);
    let f = with_threads(settings.threads, || block::gather(shape, &samples, settings.gather_rays, settings.seed));
    println!("\n| prior | enrichment | uniform light | held-out lights |\n|---|---|---|---|");
    for (grid, unit, enrich) in [(6, false, true), (6, false, false), (6, true, true), (6, true, false), (8, true, true)] {
        let mut l_d = block::prior(shape, &samples, (grid, settings.prior_lattice), settings.light_radius);
        if unit {
            l_d.column_iter_mut().for_each(|mut c| c /= c.norm());
        }
        let ops = block::reduce(shape, samples.clone(), &f, &l_d, &BlockSettings { enrich, ..settings.clone() });
        let uniform = (ops.indirect(&DVector::from_element(samples.len(), 1.0)) - &f * DVector::from_element(samples.len(), 1.0)).amax();
        let held_out = block::transfer_error(&ops, &f, &scattered_points(64, 0.25, 0.75), settings.light_radius);
        let prior = format!("{}{grid}^3 lights", if unit { "unit-norm columns, " } else { "as traced, " });
        println!("| {prior} | {} | {uniform:.3} | {held_out:.3} |", if enrich { "on" } else { "off" });
    }
}
