//! A level as the run time takes it (§6.3, §7.3), section `mrt-level` (keyed to the scene):
//! every block's dictionary shape and rows, the receivers with T_b->r's matrices per source
//! block, the level's samples (where each stands, its albedo, its texel of the light map) and
//! the padded atlas's copy records, each block's corners and the meshes the light volume lights;
//! plus [`LevelData::indirect`], the CPU evaluator of §7.3 steps 1-6 on exactly these tables
//! (and `volume`'s of steps 8-9): the oracle of the GPU passes.
//!
//! A level sample is a block's own sample: blocks in order, each block's samples as
//! `Samples::new(its shape, grid)` orders them.

use super::dictionary::Dictionary;
use super::Face;
use crate::artifact::{fail, Artifact, ArtifactError, Key, PageLayout, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::Scene;
use glam::Vec3;

pub const SECTION: &str = "mrt-level";
pub const SECTION_VERSION: u32 = 3;
const BIN: &str = "mrt-level.bin";
const MAGIC: &[u8; 8] = b"RLMRTL03";

/// The most coefficients a level's feedback may couple (blocks x k_max): its matrices are
/// D^2 values a channel.
pub const MAX_FEEDBACK: usize = 1 << 14;

/// A receiver row on one of the block's openings: no sample.
pub const NONE: u32 = u32::MAX;

#[derive(Clone, Debug, PartialEq)]
pub struct LevelBlock {
    /// Its shape's index in the dictionary.
    pub shape: u32,
    /// The quarter turns about +y that take the dictionary shape to the block (`Shape::canonical`).
    pub turns: u32,
    /// For each of the dictionary shape's samples, the level sample it stands for.
    pub rows: Vec<u32>,
}

/// Light arriving at one block through one opening (§6.3).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelReceiver {
    pub block: u32,
    /// The side face of the block the light enters through.
    pub entry: Face,
    /// For each canonical receiver sample, the level sample it lands on (or [`NONE`]).
    pub rows: Vec<u32>,
    /// (source block, T_rlf->r times the paths' turns times R_b->rlf: k_r x the source
    /// shape's k, column-major).
    pub sources: Vec<(u32, Vec<f32>)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelSample {
    /// World position and unit normal (into the block).
    pub position: Vec3,
    pub normal: Vec3,
    /// The diffuse albedo of the surface mapped there (0: no surface).
    pub albedo: Vec3,
    /// Its texel of the light map (an index in atlas texel order).
    pub texel: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LevelData {
    /// The checksum of the dictionary file the level was made with.
    pub dictionary: String,
    pub blocks: Vec<LevelBlock>,
    pub receivers: Vec<LevelReceiver>,
    pub samples: Vec<LevelSample>,
    /// The padded atlas (§6-7): (written texel, the sample texel it copies).
    pub copies: Vec<[u32; 2]>,
    /// (I - K)^-1 for red, green and blue (D x D each, column-major, D = blocks x k_max):
    /// K takes coefficients b (a block's modes at block * k_max + mode) to those of the light
    /// one bounce of them sends back, rho (U_b b + U_r T_b->r b); its fixed point is every
    /// bounce of §7.3's feedback.
    pub feedback: Vec<f32>,
    pub layout: PageLayout,
    /// Each block's eight corners (`proxy::Proxy::corners`), for locating the volume's points.
    pub corners: Vec<[Vec3; 8]>,
    /// The scene's meshes lit by the light volume (`extras.relume.mrt.dynamic`), ascending.
    pub dynamic: Vec<u32>,
}

impl LevelData {
    /// §7.3 step 2 (eq. 3): each block's coefficients b = T_d->b l for the radiosity `light`
    /// (rho E) at every level sample; rgb, the block's shape's k each. Sums in f64, in the
    /// tables' order.
    pub fn coefficients(&self, dictionary: &Dictionary, light: &[Vec3]) -> Vec<Vec<Vec3>> {
        self.blocks
            .iter()
            .map(|block| {
                let ops = &dictionary.blocks[block.shape as usize];
                let (n, k) = (ops.samples, ops.modes);
                (0..k).map(|m| sum3((0..n).map(|j| (ops.t_d_b[j * k + m], light[block.rows[j] as usize])))).collect()
            })
            .collect()
    }

    /// §7.3 step 4 (§6.3): each receiver's r = sum over its sources of T_b->r b (k_r each).
    pub fn received(&self, dictionary: &Dictionary, b: &[Vec<Vec3>]) -> Vec<Vec<Vec3>> {
        let k_r = dictionary.interfaces.response_modes;
        self.receivers
            .iter()
            .map(|receiver| {
                (0..k_r)
                    .map(|m| {
                        let terms = receiver.sources.iter().flat_map(|(source, matrix)| {
                            let b = &b[*source as usize];
                            (0..b.len()).map(move |j| (matrix[j * k_r + m], b[j]))
                        });
                        sum3(terms)
                    })
                    .collect()
            })
            .collect()
    }

    /// §7.3 steps 3 and 5: each level sample's indirect irradiance, U_b b of its block plus
    /// U_r r of every receiver landing on it.
    pub fn response(&self, dictionary: &Dictionary, b: &[Vec<Vec3>], r: &[Vec<Vec3>]) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; self.samples.len()];
        for (block, b) in self.blocks.iter().zip(b) {
            let n = dictionary.blocks[block.shape as usize].samples;
            let u_b = &dictionary.blocks[block.shape as usize].u_b;
            for (row, &sample) in block.rows.iter().enumerate() {
                out[sample as usize] += sum3(b.iter().enumerate().map(|(m, b)| (u_b[m * n + row], *b)));
            }
        }
        let i = &dictionary.interfaces;
        let n_r = i.u_r.len() / i.response_modes;
        for (receiver, r) in self.receivers.iter().zip(r) {
            for (row, &sample) in receiver.rows.iter().enumerate().filter(|(_, s)| **s != NONE) {
                out[sample as usize] += sum3(r.iter().enumerate().map(|(m, r)| (i.u_r[m * n_r + row], *r)));
            }
        }
        out
    }

    /// One bounce (§7.3 steps 2-5): the indirect irradiance at every level sample for the
    /// radiosity `light` (rho E) there.
    pub fn bounce(&self, dictionary: &Dictionary, light: &[Vec3]) -> Vec<Vec3> {
        let b = self.coefficients(dictionary, light);
        let r = self.received(dictionary, &b);
        self.response(dictionary, &b, &r)
    }

    /// The coefficients with every bounce fed back (§7.3's feedback at its fixed point):
    /// b = (I - K)^-1 b0 per colour channel, K the coefficients of the light one bounce of b
    /// sends back (`feedback`).
    pub fn fed_back(&self, dictionary: &Dictionary, b0: &[Vec<Vec3>]) -> Vec<Vec<Vec3>> {
        let k_max = k_max(dictionary);
        let d = self.blocks.len() * k_max;
        assert_eq!(self.feedback.len(), 3 * d * d, "the level's feedback is solved (baker::bake_level)");
        let flat: Vec<Vec3> = b0.iter().flat_map(|b| (0..k_max).map(move |m| b.get(m).copied().unwrap_or(Vec3::ZERO))).collect();
        let solved: Vec<Vec3> = (0..d)
            .map(|i| {
                let channel = |c: usize| {
                    let m = &self.feedback[c * d * d..(c + 1) * d * d];
                    (0..d).map(|j| m[j * d + i] as f64 * flat[j][c] as f64).sum::<f64>() as f32
                };
                Vec3::new(channel(0), channel(1), channel(2))
            })
            .collect();
        b0.iter().enumerate().map(|(block, b)| solved[block * k_max..block * k_max + b.len()].to_vec()).collect()
    }

    /// The indirect irradiance at every level sample for the direct irradiance `direct`
    /// there (§7.3 steps 2-5): every bounce (`feedback`) or the first only.
    pub fn indirect(&self, dictionary: &Dictionary, direct: &[Vec3], feedback: bool) -> Vec<Vec3> {
        assert_eq!(direct.len(), self.samples.len(), "direct light for every level sample");
        let light: Vec<Vec3> = direct.iter().zip(&self.samples).map(|(e, s)| *e * s.albedo).collect();
        let b0 = self.coefficients(dictionary, &light);
        let b = if feedback { self.fed_back(dictionary, &b0) } else { b0 };
        let r = self.received(dictionary, &b);
        self.response(dictionary, &b, &r)
    }
}

/// The most modes of a dictionary shape: the stride of a level's coefficients per block.
pub fn k_max(dictionary: &Dictionary) -> usize {
    dictionary.blocks.iter().map(|b| b.modes).max().unwrap_or(1)
}

/// The sum of `weight * value`, in f64.
fn sum3(terms: impl Iterator<Item = (f32, Vec3)>) -> Vec3 {
    let sum = terms.fold([0.0f64; 3], |mut s, (w, v)| {
        (0..3).for_each(|c| s[c] += w as f64 * v[c] as f64);
        s
    });
    Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
}

pub fn section(level: &LevelData, summary: serde_json::Value) -> Section {
    let mut w = Writer::new(MAGIC);
    let checksum = level.dictionary.as_bytes();
    w.u32s(&[checksum.len() as u32]);
    w.u32s(&checksum.iter().map(|&c| c as u32).collect::<Vec<_>>());
    w.u32s(&[level.layout.width, level.layout.height, level.layout.pages]);
    w.u32s(&[level.blocks.len() as u32, level.receivers.len() as u32, level.samples.len() as u32, level.copies.len() as u32]);
    for block in &level.blocks {
        w.u32s(&[block.shape, block.turns, block.rows.len() as u32]);
        w.u32s(&block.rows);
    }
    for receiver in &level.receivers {
        w.u32s(&[receiver.block, receiver.entry.index() as u32, receiver.rows.len() as u32, receiver.sources.len() as u32]);
        w.u32s(&receiver.rows);
        for (source, matrix) in &receiver.sources {
            w.u32s(&[*source]);
            w.f32s(matrix);
        }
    }
    for s in &level.samples {
        w.f32s(&[s.position.to_array(), s.normal.to_array(), s.albedo.to_array()].concat());
        w.u32s(&[s.texel]);
    }
    w.u32s(&level.copies.iter().flatten().copied().collect::<Vec<_>>());
    w.f32s(&level.feedback);
    level.corners.iter().for_each(|c| w.f32s(&c.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>()));
    w.u32s(&[level.dynamic.len() as u32]);
    w.u32s(&level.dynamic);
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The level of `artifact` for `scene`, checked against `dictionary` (read with its
/// `checksum`): refused when made with another dictionary, or when a table is out of range.
pub fn read(artifact: &Artifact, scene: &Scene, dictionary: &Dictionary, checksum: &str) -> Result<LevelData, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "MRT level")?;
    let length = r.u32("the dictionary checksum's length")? as usize;
    if length > 64 {
        return Err(fail(&path, format!("a dictionary checksum of {length} characters"), REBAKE));
    }
    let named: String = r.u32s(length, "the dictionary checksum")?.into_iter().map(|c| char::from_u32(c).unwrap_or('?')).collect();
    if named != checksum {
        let problem = format!("the level was made with the dictionary {named}, not the artifact's {checksum}");
        return Err(fail(&path, problem, "bake the level again with this dictionary (relume bake SCENE --method mrt)"));
    }
    let bad = |what: String| fail(&path, what, REBAKE);
    let [width, height, pages] = [r.u32("the atlas width")?, r.u32("the atlas height")?, r.u32("the atlas pages")?];
    let layout = PageLayout { width, height, pages };
    if width == 0 || height == 0 || pages != 1 || width > 16384 || height > 16384 {
        return Err(bad(format!("an impossible light map of {width} x {height} x {pages}")));
    }
    let counts = r.u32s(4, "the table sizes")?;
    let (block_count, receiver_count, sample_count, copy_count) =
        (counts[0] as usize, counts[1] as usize, counts[2] as usize, counts[3] as usize);
    if sample_count > layout.texel_count() || copy_count > layout.texel_count() || receiver_count > 4 * block_count {
        return Err(bad(format!(
            "{sample_count} samples, {copy_count} copies and {receiver_count} receivers for {block_count} blocks on {} texels",
            layout.texel_count()
        )));
    }
    let in_range = |v: &[u32], end: usize, none: bool| v.iter().all(|&x| (x as usize) < end || (none && x == NONE));
    let mut blocks = Vec::with_capacity(block_count.min(1 << 16));
    for b in 0..block_count {
        let (shape, turns, n) = (r.u32("a block's shape")? as usize, r.u32("a block's turns")?, r.u32("a block's row count")? as usize);
        let ops = dictionary
            .blocks
            .get(shape)
            .ok_or_else(|| bad(format!("block {b} has shape {shape}; the dictionary has {}", dictionary.blocks.len())))?;
        if n != ops.samples || turns > 3 {
            return Err(bad(format!(
                "block {b} has {n} rows and {turns} quarter turns; its shape has {} samples, and 0-3 turns",
                ops.samples
            )));
        }
        let rows = r.u32s(n, "a block's rows")?;
        if !in_range(&rows, sample_count, false) {
            return Err(bad(format!("block {b} names a sample past the level's {sample_count}")));
        }
        blocks.push(LevelBlock { shape: shape as u32, turns, rows });
    }
    let interfaces = &dictionary.interfaces;
    let n_r = interfaces.u_r.len() / interfaces.response_modes;
    let mut receivers = Vec::with_capacity(receiver_count);
    for i in 0..receiver_count {
        let (block, entry) = (r.u32("a receiver's block")?, r.u32("a receiver's entry face")? as usize);
        let (rows, sources) = (r.u32("a receiver's row count")? as usize, r.u32("a receiver's source count")? as usize);
        let entry = Face::ALL.get(entry).copied().filter(|f| f.axis != 1);
        if block as usize >= block_count || rows != n_r || sources > block_count || entry.is_none() {
            return Err(bad(format!(
                "receiver {i}: block {block}, {rows} rows, {sources} sources, entry {entry:?} (the level has {block_count} blocks, a receiver {n_r} rows and a side face)"
            )));
        }
        let rows = r.u32s(rows, "a receiver's rows")?;
        if !in_range(&rows, sample_count, true) {
            return Err(bad(format!("receiver {i} names a sample past the level's {sample_count}")));
        }
        let mut from = Vec::with_capacity(sources);
        for _ in 0..sources {
            let source = r.u32("a source block")? as usize;
            let shape = blocks.get(source).ok_or_else(|| bad(format!("receiver {i} names source block {source} of {block_count}")))?.shape;
            let matrix = r.f32s(interfaces.response_modes * dictionary.blocks[shape as usize].modes, "a source's transfer")?;
            if matrix.iter().any(|v| !crate::artifact::stored(*v)) {
                return Err(bad(format!("receiver {i}'s transfer holds a value that is not finite (or past 1e9)")));
            }
            from.push((source as u32, matrix));
        }
        receivers.push(LevelReceiver { block, entry: entry.expect("checked"), rows, sources: from });
    }
    // Each sample stands for exactly one row of one block (the passes read its block's U_b).
    let mut owned = vec![false; sample_count];
    for (b, block) in blocks.iter().enumerate() {
        for &s in &block.rows {
            if std::mem::replace(&mut owned[s as usize], true) {
                return Err(bad(format!("block {b} names sample {s}, which another row names too")));
            }
        }
    }
    if let Some(s) = owned.iter().position(|o| !o) {
        return Err(bad(format!("sample {s} belongs to no block")));
    }
    let mut samples = Vec::with_capacity(sample_count.min(1 << 16));
    for s in 0..sample_count {
        let f = r.f32s(9, "a sample")?;
        let texel = r.u32("a sample's texel")?;
        let sample = LevelSample {
            position: Vec3::from_slice(&f[0..3]),
            normal: Vec3::from_slice(&f[3..6]),
            albedo: Vec3::from_slice(&f[6..9]),
            texel,
        };
        if !f.iter().all(|v| crate::artifact::stored(*v)) || texel as usize >= layout.texel_count() {
            return Err(bad(format!(
                "sample {s} is not finite (or past 1e9) or names a texel past the light map's {}",
                layout.texel_count()
            )));
        }
        samples.push(sample);
    }
    let flat = r.u32s(2 * copy_count, "the copy records")?;
    if !in_range(&flat, layout.texel_count(), false) {
        return Err(bad(format!("a copy record names a texel past the light map's {}", layout.texel_count())));
    }
    let d = block_count * k_max(dictionary);
    if d > MAX_FEEDBACK {
        return Err(bad(format!("{block_count} blocks of {} modes: a feedback past {MAX_FEEDBACK} coefficients", k_max(dictionary))));
    }
    let feedback = r.f32s(3 * d * d, "the feedback")?;
    if feedback.iter().any(|v| !crate::artifact::stored(*v)) {
        return Err(bad("the feedback holds a value that is not finite (or past 1e9)".into()));
    }
    let mut corners = Vec::with_capacity(block_count.min(1 << 16));
    for b in 0..block_count {
        let f = r.f32s(24, "a block's corners")?;
        if !f.iter().all(|v| v.is_finite()) {
            return Err(bad(format!("block {b}'s corners are not finite")));
        }
        corners.push(std::array::from_fn(|i| Vec3::from_slice(&f[3 * i..3 * i + 3])));
    }
    let count = r.u32("the dynamic mesh count")? as usize;
    let dynamic = r.u32s(count.min(scene.meshes.len() + 1), "the dynamic meshes")?;
    if count > scene.meshes.len() || !dynamic.windows(2).all(|w| w[0] < w[1]) || !in_range(&dynamic, scene.meshes.len(), false) {
        return Err(bad(format!("{count} dynamic meshes, not ascending indices of the scene's {}", scene.meshes.len())));
    }
    r.finish("the dynamic meshes")?;
    let copies = flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    Ok(LevelData { dictionary: named, blocks, receivers, samples, copies, layout, feedback, corners, dynamic })
}
