//! The run time's transfer on the CPU (§7.3 steps 2-5): for each block, b = T_d->b l_d on its
//! dictionary shape's samples (the block's own, turned) and its own indirect light U_b b; then
//! r = T_b->r b for each block entered through each of its openings, and the response U_r r
//! turned onto that block. The oracle the GPU passes are to be checked against.

use super::block::BlockOperators;
use super::interface::Interfaces;
use super::level::{opposite, traverse, Level};
use super::level_data::{LevelBlock, LevelData, LevelReceiver, NONE};
use super::{Face, Shape};
use nalgebra::{DMatrix, DVector};

/// Light arriving at one block through one opening: from which sources, by which matrix
/// (k_r x k_self: T_rlf->r times the sum over paths of the turns times R_b->rlf).
struct Receiver {
    block: usize,
    entry: Face,
    /// For each canonical receiver sample, the block's own sample (None: an opening).
    rows: Vec<Option<usize>>,
    sources: Vec<(usize, DMatrix<f64>)>,
}

/// A level's transfer: each block's dictionary shape and rows, and T_b->r by receiver.
pub struct LevelTransfer {
    /// Per block: its dictionary shape's index, the quarter turns to it, and per dictionary
    /// sample its own sample.
    blocks: Vec<(usize, u32, Vec<usize>)>,
    receivers: Vec<Receiver>,
    /// Own sample counts, per block.
    sizes: Vec<usize>,
}

impl LevelTransfer {
    /// T_b->r by traversal to `d_max` crossings from every block (§6.3); `dictionary` must be
    /// `Shape::dictionary`'s shapes' operators in that order, and `interfaces` built from them.
    pub fn new(level: &Level, dictionary: &[BlockOperators], interfaces: &Interfaces, d_max: usize) -> Result<LevelTransfer, String> {
        let shapes: Vec<Shape> = dictionary.iter().map(|d| d.shape).collect();
        if shapes != Shape::dictionary() {
            return Err(format!("the level's operators need the 2D dictionary's six shapes in order, not {shapes:?}"));
        }
        let grid = dictionary[0].samples.grid;
        let blocks: Vec<(usize, u32, Vec<usize>)> = (0..level.len())
            .map(|i| {
                let (index, turns) = level.shape(i).canonical();
                (index, turns, level.own_rows(&dictionary[index].samples, i))
            })
            .collect();
        let sizes = (0..level.len()).map(|i| super::Samples::new(level.shape(i), grid).len()).collect();
        let mut receivers: Vec<Receiver> = Vec::new();
        for source in 0..level.len() {
            let from = |c: super::level::Crossing| {
                let (index, face) = level.dictionary_face(c.block, c.face);
                interfaces.from_block(index, face).expect("the dictionary's interfaces include every shape's openings").clone()
            };
            let reached = traverse(level, source, d_max, from, |t| interfaces.turn(t).clone());
            let mut order: Vec<_> = reached.into_iter().collect();
            order.sort_by_key(|(c, _)| (c.block, c.face.index(), c.to));
            for (crossing, light) in order {
                let entry: Face = opposite(crossing.face);
                let matrix = &interfaces.t_rlf_r * light;
                match receivers.iter_mut().find(|r| (r.block, r.entry) == (crossing.to, entry)) {
                    Some(receiver) => receiver.sources.push((source, matrix)),
                    None => receivers.push(Receiver {
                        block: crossing.to,
                        entry,
                        rows: level.receiver_rows(&interfaces.receiver, crossing.to, entry),
                        sources: vec![(source, matrix)],
                    }),
                }
            }
        }
        Ok(LevelTransfer { blocks, receivers, sizes })
    }

    /// The indirect light of every block (its own samples) for its direct light `l_d` (its
    /// own samples): U_b b plus every arriving U_r r.
    pub fn indirect(
        &self,
        dictionary: &[BlockOperators],
        interfaces: &Interfaces,
        l_d: &[DVector<f64>],
    ) -> Result<Vec<DVector<f64>>, String> {
        let given: Vec<usize> = l_d.iter().map(|l| l.len()).collect();
        if given != self.sizes {
            return Err(format!("direct light for blocks of {given:?} samples; the level's blocks have {:?}", self.sizes));
        }
        let mut out: Vec<DVector<f64>> = self.sizes.iter().map(|&n| DVector::zeros(n)).collect();
        let b: Vec<DVector<f64>> = self
            .blocks
            .iter()
            .enumerate()
            .map(|(i, (index, _, rows))| {
                let ops = &dictionary[*index];
                let on_shape = DVector::from_iterator(rows.len(), rows.iter().map(|&r| l_d[i][r]));
                let b = &ops.t_d_b * on_shape;
                let own = &ops.u_b * &b;
                rows.iter().zip(own.iter()).for_each(|(&r, v)| out[i][r] += v);
                b
            })
            .collect();
        for receiver in &self.receivers {
            let r = receiver.sources.iter().fold(DVector::zeros(interfaces.t_rlf_r.nrows()), |r, (source, m)| r + m * &b[*source]);
            let response = &interfaces.u_r * r;
            for (row, v) in receiver.rows.iter().zip(response.iter()) {
                if let Some(j) = row {
                    out[receiver.block][*j] += v;
                }
            }
        }
        Ok(out)
    }
}

impl LevelTransfer {
    /// The tables the run time takes (`LevelData`): level samples numbered block by block, so
    /// `samples` (the mapped scene's, in that order) fit; made with the dictionary of `checksum`;
    /// the feedback, the corners and the dynamic meshes left empty (`baker::bake_level` fills them).
    pub fn level_data(&self, checksum: String, samples: &super::map::Mapped) -> LevelData {
        let offsets: Vec<u32> = self.sizes.iter().scan(0u32, |at, &n| Some(std::mem::replace(at, *at + n as u32))).collect();
        let blocks = self
            .blocks
            .iter()
            .zip(&offsets)
            .map(|((shape, turns, rows), &first)| LevelBlock {
                shape: *shape as u32,
                turns: *turns,
                rows: rows.iter().map(|&r| first + r as u32).collect(),
            })
            .collect();
        let receivers = self
            .receivers
            .iter()
            .map(|r| LevelReceiver {
                block: r.block as u32,
                entry: r.entry,
                rows: r.rows.iter().map(|row| row.map_or(NONE, |j| offsets[r.block] + j as u32)).collect(),
                sources: r.sources.iter().map(|(s, m)| (*s as u32, m.iter().map(|&v| v as f32).collect())).collect(),
            })
            .collect();
        LevelData {
            dictionary: checksum,
            blocks,
            receivers,
            samples: samples.samples.clone(),
            copies: samples.copies.clone(),
            layout: samples.layout,
            feedback: Vec::new(),
            corners: Vec::new(),
            dynamic: Vec::new(),
        }
    }
}
