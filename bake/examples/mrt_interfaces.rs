//! Transfer between blocks (Loos et al. 2011, §5.1 and §6.3) against brute force, for
//! docs/BENCHMARKS.md: a column of blocks along +z with one light in the first; the relative
//! error of the level's transfer onto the last block (next door, and one corridor block
//! further) against a brute-force walk, by what the operators keep.
//!
//!     cargo run --release -p relume-bake --example mrt_interfaces

// Shared with the tests, which use more of it.
#[path = "../tests/common/mrt_oracle.rs"]
#[allow(dead_code)]
mod oracle;

use glam::Vec3;
use nalgebra::DVector;
use relume_bake::mrt::block::{self, BlockOperators};
use relume_bake::mrt::evaluate::LevelTransfer;
use relume_bake::mrt::interface::{self, InterfaceSettings};
use relume_bake::mrt::level::Level;
use relume_bake::mrt::{BlockSettings, Samples, Shape};
use std::time::Instant;

fn main() {
    let base = InterfaceSettings { positions: 8, directions: 12, supersamples: 2, gather_rays: 4096, ..InterfaceSettings::default() };
    println!("| k_self | lightfield (positions^2 x directions^2) | k_rlf | k_r | next door | corridor | L_imp b against l_d, next door | build |");
    println!("|---|---|---|---|---|---|---|---|");
    let paper_resolution = InterfaceSettings { positions: 12, directions: 24, ..base.clone() };
    let rows = [
        (32, base.clone()),
        (32, InterfaceSettings { lightfield_modes: 16, ..base.clone() }),
        (32, InterfaceSettings { response_modes: 64, ..base.clone() }),
        (32, paper_resolution),
        (64, base.clone()),
    ];
    for (k_self, settings) in rows {
        let clock = Instant::now();
        let dictionary: Vec<BlockOperators> = Shape::dictionary()
            .iter()
            .map(|&shape| block::build(shape, &BlockSettings { gather_rays: 4096, modes: k_self, ..BlockSettings::default() }))
            .collect();
        let ops = interface::build(&dictionary, &settings);
        let built = clock.elapsed().as_secs_f64();
        let errors = [2, 3].map(|length| column_error(&dictionary, &ops, length));
        println!(
            "| {k_self} | {}^2 x {}^2 | {} | {} | {:.4} | {:.4} | {:.4} | {built:.1} s |",
            settings.positions,
            settings.directions,
            settings.lightfield_modes,
            settings.response_modes,
            errors[0].0,
            errors[1].0,
            errors[0].1
        );
    }
}

/// The relative error on the last of `length` blocks in a column, lit in the first; and the
/// error a perfect transfer would still have from the source's own reduction: the brute-force
/// bounce of L_imp b (the direct light as b keeps it) against that of l_d.
fn column_error(dictionary: &[BlockOperators], ops: &interface::Interfaces, length: i32) -> (f64, f64) {
    let cells: Vec<(i32, i32)> = (0..length).map(|z| (0, z)).collect();
    let level = Level::new(cells.clone()).expect("distinct cells");
    let transfer = LevelTransfer::new(&level, dictionary, ops, 8).expect("the dictionary in order");
    let samples: Vec<Samples> = (0..cells.len()).map(|i| Samples::new(level.shape(i), 16)).collect();
    let mut l_d: Vec<DVector<f64>> = samples.iter().map(|s| DVector::zeros(s.len())).collect();
    l_d[0] = block::direct_irradiance(level.shape(0), &samples[0], Vec3::new(0.45, 0.6, 0.4), 0.05);
    let estimate = transfer.indirect(dictionary, ops, &l_d).expect("the level's sizes");
    let truth = oracle::bounce(&cells, &samples, &l_d, 4096);
    let last = cells.len() - 1;
    let relative = |a: &DVector<f64>, b: &DVector<f64>| (a - b).norm() / b.norm();
    let (index, _) = level.shape(0).canonical();
    let rows = level.own_rows(&dictionary[index].samples, 0);
    let on_shape = DVector::from_iterator(rows.len(), rows.iter().map(|&r| l_d[0][r]));
    let kept = &dictionary[index].l_imp * (&dictionary[index].t_d_b * on_shape);
    let mut projected = l_d.clone();
    rows.iter().zip(kept.iter()).for_each(|(&r, v)| projected[0][r] = *v);
    let through = oracle::bounce(&cells, &samples, &projected, 4096);
    (relative(&estimate[last], &truth[last]), relative(&through[last], &truth[last]))
}
