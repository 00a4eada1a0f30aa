//! The level's and the dictionary's tables as the passes read them (the layouts mod.rs lists),
//! flattened on the CPU once, at creation.

use super::MrtPush;
use glam::{UVec2, UVec4, Vec3, Vec4};
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::level_data::{LevelData, NONE};
use relume_bake::mrt::proxy;
use relume_bake::mrt::volume::{self, OUTSIDE, ROWS};

/// One block as the volume passes read it (shaders/mrt/volume.glsl's VolumeBlock).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct VolumeBlock {
    info: UVec4,
    receivers: UVec4,
    lo: Vec4,
    hi: Vec4,
    corners: [Vec4; 8],
}

pub(super) struct Tables {
    pub samples: Vec<Vec4>,
    pub shapes: Vec<UVec4>,
    pub operators: Vec<f32>,
    pub blocks: Vec<UVec2>,
    pub rows: Vec<u32>,
    pub receivers: Vec<UVec2>,
    pub sources: Vec<UVec2>,
    pub matrices: Vec<f32>,
    pub sample_rows: Vec<UVec4>,
    pub texel_samples: Vec<u32>,
    pub copies: Vec<UVec2>,
    pub volume_blocks: Vec<VolumeBlock>,
    pub push: MrtPush,
    feedback_bytes: usize,
}

/// `values`, or one zero when there are none (a buffer cannot be empty).
fn non_empty<T: Default>(mut values: Vec<T>) -> Vec<T> {
    if values.is_empty() {
        values.push(T::default());
    }
    values
}

impl Tables {
    /// The tables of `level` made with `dictionary`; refused when they do not fit each other
    /// (a level as `relume_bake::mrt::level_data::read` or `baker::bake_level` gives it fits).
    pub fn new(dictionary: &Dictionary, level: &LevelData) -> Result<Tables, String> {
        fits(dictionary, level)?;
        let mut operators = Vec::new();
        let mut shapes = Vec::new();
        for block in &dictionary.blocks {
            let t_d_b = operators.len() as u32;
            operators.extend_from_slice(&block.t_d_b);
            let u_b = operators.len() as u32;
            operators.extend_from_slice(&block.u_b);
            shapes.push(UVec4::new(block.samples as u32, block.modes as u32, t_d_b, u_b));
        }
        let u_r = operators.len() as u32;
        operators.extend_from_slice(&dictionary.interfaces.u_r);
        let u_bvol: Vec<u32> = dictionary
            .blocks
            .iter()
            .map(|block| {
                let at = operators.len() as u32;
                operators.extend_from_slice(&block.u_bvol);
                at
            })
            .collect();
        let u_rvol = operators.len() as u32;
        dictionary.interfaces.u_rvol.iter().for_each(|u| operators.extend_from_slice(u));
        let k_max = dictionary.blocks.iter().map(|b| b.modes as u32).max().unwrap_or(1);
        let (k_r, n_r) =
            (dictionary.interfaces.response_modes as u32, (dictionary.interfaces.u_r.len() / dictionary.interfaces.response_modes) as u32);
        let sample_count = level.samples.len();
        // Per sample: (block, row), then up to four (receiver, row).
        let mut sample_rows = vec![[UVec4::ZERO, UVec4::splat(NONE), UVec4::ZERO]; sample_count];
        let mut blocks = Vec::with_capacity(level.blocks.len());
        let mut rows = Vec::new();
        for (b, block) in level.blocks.iter().enumerate() {
            blocks.push(UVec2::new(block.shape, rows.len() as u32));
            for (row, &s) in block.rows.iter().enumerate() {
                sample_rows[s as usize][0] = UVec4::new(b as u32, row as u32, 0, 0);
            }
            rows.extend_from_slice(&block.rows);
        }
        let (mut receivers, mut sources, mut matrices) = (Vec::new(), Vec::new(), Vec::new());
        for (i, receiver) in level.receivers.iter().enumerate() {
            receivers.push(UVec2::new(sources.len() as u32, receiver.sources.len() as u32));
            for (source, matrix) in &receiver.sources {
                sources.push(UVec2::new(*source, matrices.len() as u32));
                matrices.extend_from_slice(matrix);
            }
            for (row, &s) in receiver.rows.iter().enumerate().filter(|(_, s)| **s != NONE) {
                let at = &mut sample_rows[s as usize];
                let slot =
                    (0..4).find(|&k| at[1][k] == NONE).ok_or_else(|| format!("sample {s} is reached through more than four openings"))?;
                at[1][slot] = i as u32;
                at[2][slot] = row as u32;
            }
        }
        let mut texel_samples = vec![NONE; level.layout.texel_count()];
        for (s, sample) in level.samples.iter().enumerate() {
            texel_samples[sample.texel as usize] = s as u32;
        }
        let volume_blocks = volume_blocks(dictionary, level, &u_bvol)?;
        let samples = level.samples.iter().flat_map(|s| [s.position.extend(1.0), s.normal.extend(0.0), s.albedo.extend(0.0)]).collect();
        let push = MrtPush {
            sample_count: sample_count as u32,
            block_count: level.blocks.len() as u32,
            k_max,
            receiver_count: level.receivers.len() as u32,
            k_r,
            n_r,
            texel_count: texel_samples.len() as u32,
            copy_count: level.copies.len() as u32,
            width: level.layout.width,
            feedback: 1,
            u_r,
            u_rvol,
            dynamic_count: 0,
        };
        Ok(Tables {
            samples: non_empty(samples),
            shapes,
            operators,
            blocks: non_empty(blocks),
            rows: non_empty(rows),
            receivers: non_empty(receivers),
            sources: non_empty(sources),
            matrices: non_empty(matrices),
            sample_rows: non_empty(sample_rows.into_iter().flatten().collect()),
            texel_samples,
            copies: non_empty(level.copies.iter().map(|c| UVec2::from(*c)).collect()),
            volume_blocks: non_empty(volume_blocks),
            push,
            feedback_bytes: level.feedback.len() * 4,
        })
    }

    /// Refuses tables a storage buffer of `limit` bytes cannot span.
    pub fn check(&self, limit: u64) -> Result<(), String> {
        for (name, bytes) in
            [("operators", self.operators.len() * 4), ("matrices (T_b->r)", self.matrices.len() * 4), ("feedback", self.feedback_bytes)]
        {
            if bytes as u64 > limit {
                return Err(format!("the {name} take {bytes} bytes, more than the {limit} bytes one storage buffer may span; use fewer blocks, a smaller d-max or fewer modes"));
            }
        }
        Ok(())
    }
}

/// Each block's volume table: where its shape's U_bvol starts (`u_bvol`, per shape), its modes
/// and turns, its receivers with the side each enters through in the shape's frame, its corners
/// and bounds widened by OUTSIDE of its mean edge.
fn volume_blocks(dictionary: &Dictionary, level: &LevelData, u_bvol: &[u32]) -> Result<Vec<VolumeBlock>, String> {
    let mut out: Vec<VolumeBlock> = level
        .blocks
        .iter()
        .zip(&level.corners)
        .map(|(block, corners)| {
            let mean = proxy::mean_edge(&corners.map(|c| c.as_dvec3())) as f32;
            let (lo, hi) = corners.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
            let shape = block.shape as usize;
            VolumeBlock {
                info: UVec4::new(u_bvol[shape], dictionary.blocks[shape].modes as u32, block.turns, 0),
                receivers: UVec4::splat(NONE),
                lo: (lo - OUTSIDE * mean).extend(0.0),
                hi: (hi + OUTSIDE * mean).extend(0.0),
                corners: corners.map(|c| c.extend(1.0)),
            }
        })
        .collect();
    for (i, receiver) in level.receivers.iter().enumerate() {
        let at = &mut out[receiver.block as usize].receivers;
        let slot = (0..4).find(|&k| at[k] == NONE).ok_or_else(|| format!("block {} has more than four receivers", receiver.block))?;
        at[slot] = 4 * i as u32 + level.canonical_side(receiver) as u32;
    }
    Ok(out)
}

/// Whether the level's tables index the dictionary's operators and its own samples in range:
/// shapes, row counts, transfer sizes and the solved feedback.
fn fits(dictionary: &Dictionary, level: &LevelData) -> Result<(), String> {
    let samples = level.samples.len();
    let d = level.blocks.len() * relume_bake::mrt::level_data::k_max(dictionary);
    let k_r = dictionary.interfaces.response_modes;
    for (b, block) in level.blocks.iter().enumerate() {
        let ops =
            dictionary.blocks.get(block.shape as usize).ok_or(format!("block {b}'s shape {} is not the dictionary's", block.shape))?;
        if block.rows.len() != ops.samples || block.rows.iter().any(|&s| s as usize >= samples) {
            return Err(format!("block {b}'s rows do not fit its shape ({} samples) and the level's {samples}", ops.samples));
        }
    }
    for (i, receiver) in level.receivers.iter().enumerate() {
        let sizes = receiver
            .sources
            .iter()
            .all(|(s, m)| level.blocks.get(*s as usize).is_some_and(|b| m.len() == k_r * dictionary.blocks[b.shape as usize].modes));
        if !sizes
            || receiver.block as usize >= level.blocks.len()
            || receiver.rows.len() * k_r != dictionary.interfaces.u_r.len()
            || receiver.rows.iter().any(|&s| s != NONE && s as usize >= samples)
        {
            return Err(format!("receiver {i}'s rows or transfer do not fit the dictionary and the level"));
        }
    }
    if level.corners.len() != level.blocks.len()
        || dictionary.blocks.iter().any(|b| b.u_bvol.len() != ROWS * b.modes)
        || dictionary.interfaces.u_rvol.len() != volume::SIDES.len()
        || dictionary.interfaces.u_rvol.iter().any(|u| u.len() != ROWS * k_r)
        || level.receivers.iter().any(|r| volume::side(r.entry).is_none())
    {
        return Err("the level's corners or the dictionary's volume operators do not fit its blocks".into());
    }
    if level.feedback.len() != 3 * d * d {
        return Err(format!(
            "the level's feedback holds {} values, not 3 x {d}^2 (bake the level with relume_bake::mrt::baker::bake_level)",
            level.feedback.len()
        ));
    }
    if level.samples.iter().any(|s| s.texel as usize >= level.layout.texel_count())
        || level.copies.iter().flatten().any(|&t| t as usize >= level.layout.texel_count())
    {
        return Err("a sample or copy record names a texel past the light map".into());
    }
    Ok(())
}
