//! Transfer between blocks (Loos et al. 2011, §5.1) against brute force, for
//! docs/BENCHMARKS.md: a source block open at +z lit by one light, the canonical receiver
//! next door and one corridor block further; the relative error of U_r T_rlf->r R b against a
//! brute-force bounce, by what the operators keep.
//!
//!     cargo run --release -p relume-bake --example mrt_interfaces

// Shared with the tests, which use more of it.
#[path = "../tests/common/mrt_oracle.rs"]
#[allow(dead_code)]
mod oracle;

use glam::Vec3;
use relume_bake::mrt::block::{self, BlockOperators};
use relume_bake::mrt::interface::{self, InterfaceSettings};
use relume_bake::mrt::level::Turn;
use relume_bake::mrt::{BlockSettings, Face, Shape};
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
        let blocks = blocks(k_self);
        let ops = interface::build(&blocks, &settings);
        let built = clock.elapsed().as_secs_f64();
        let source = blocks.last().expect("the source");
        let l_d = block::direct_irradiance(source.shape, &source.samples, Vec3::new(0.45, 0.6, 0.4), 0.05);
        let b = &source.t_d_b * &l_d;
        let c = ops.from_block(blocks.len() - 1, Face::ALL[5]).expect("the source's opening") * &b;
        let relative = |estimate: &nalgebra::DVector<f64>, truth: &nalgebra::DVector<f64>| (estimate - truth).norm() / truth.norm();
        let next_door = oracle::brute_force(&ops.receiver, source, &l_d, 0, 4096);
        let corridor = oracle::brute_force(&ops.receiver, source, &l_d, 1, 4096);
        let projected = oracle::brute_force(&ops.receiver, source, &(&source.l_imp * &b), 0, 4096);
        println!(
            "| {k_self} | {}^2 x {}^2 | {} | {} | {:.4} | {:.4} | {:.4} | {built:.1} s |",
            settings.positions,
            settings.directions,
            settings.lightfield_modes,
            settings.response_modes,
            relative(&ops.response(&c), &next_door),
            relative(&ops.response(&(ops.turn(Turn::Ahead) * &c)), &corridor),
            relative(&projected, &next_door),
        );
    }
}

/// The dictionary's shapes and the source (open at +z), at 4,096 gather rays.
fn blocks(modes: usize) -> Vec<BlockOperators> {
    let settings = BlockSettings { gather_rays: 4096, modes, ..BlockSettings::default() };
    let mut shapes: Vec<Shape> = Shape::dictionary().to_vec();
    shapes.push(Shape::with_open(&[Face::ALL[5]]).expect("a side face"));
    shapes.iter().map(|&shape| block::build(shape, &settings)).collect()
}
