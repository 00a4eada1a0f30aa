//! The dictionary's section, `mrt-dictionary` (keyed to nothing: made once for every scene):
//! what it was made with, each shape's operators U_b, T_d->b and L_imp (§4), and the interface
//! operators R_b->rlf, the three turns, U_r and T_rlf->r (§5.1); and the light volume's U_bvol
//! per shape and U_rvol per side face (§6.5, `volume`); f32, column-major. A level
//! reads it only when it was made with the parameters the level asks for.

use super::{volume, BlockSettings, Face, InterfaceSettings, PriorLattice, Samples, Shape};
use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};

pub const SECTION: &str = "mrt-dictionary";
pub const SECTION_VERSION: u32 = 4;
pub const BIN: &str = "mrt-dictionary.bin";
const MAGIC: &[u8; 8] = b"RLMRTD04";

/// One shape's operators: `samples` (n) rows, `modes` (k) columns.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockData {
    pub shape: Shape,
    pub samples: usize,
    pub modes: usize,
    /// n x k.
    pub u_b: Vec<f32>,
    /// k x n.
    pub t_d_b: Vec<f32>,
    /// n x k.
    pub l_imp: Vec<f32>,
    /// U_bvol: volume::ROWS x k.
    pub u_bvol: Vec<f32>,
}

/// The interface operators (§5.1), for `lightfield_modes` (k_rlf) and `response_modes` (k_r).
#[derive(Clone, Debug, PartialEq)]
pub struct InterfaceData {
    pub lightfield_modes: usize,
    pub response_modes: usize,
    /// R_b->rlf (k_rlf x the shape's k) per open face of each shape, in dictionary order.
    pub from_blocks: Vec<(usize, Face, Vec<f32>)>,
    /// R_ahead, R_left, R_right (k_rlf x k_rlf).
    pub turns: [Vec<f32>; 3],
    /// U_r (the canonical receiver's n_r x k_r).
    pub u_r: Vec<f32>,
    /// T_rlf->r (k_r x k_rlf).
    pub t_rlf_r: Vec<f32>,
    /// U_rvol per side face, `volume::SIDES` order (volume::ROWS x k_r each).
    pub u_rvol: Vec<Vec<f32>>,
}

#[derive(Clone, Debug)]
pub struct Dictionary {
    /// What it was made with (threads aside: they change nothing).
    pub settings: BlockSettings,
    pub interface: InterfaceSettings,
    pub blocks: Vec<BlockData>,
    pub interfaces: InterfaceData,
}

/// The canonical receiver of the interfaces: the unit cube open at -z only, entered there.
pub fn receiver(grid: usize) -> Samples {
    Samples::new(Shape::with_open(&[Face { axis: 2, positive: false }]).expect("a side face"), grid)
}

/// The dictionary's interfaces: (shape index, open face), in dictionary order.
pub fn slots() -> Vec<(usize, Face)> {
    Shape::dictionary().iter().enumerate().flat_map(|(i, s)| s.open_faces().into_iter().map(move |f| (i, f))).collect()
}

/// The parameters a dictionary is checked against, as (name, value) in the stored order.
fn parameters(s: &BlockSettings, i: &InterfaceSettings) -> [(&'static str, u64); 16] {
    [
        ("samples-per-face", s.samples_per_face as u64),
        ("gather-rays", s.gather_rays as u64),
        ("prior-grid", s.prior_grid as u64),
        ("light-radius", s.light_radius.to_bits() as u64),
        ("prior-modes", s.prior_modes as u64),
        ("modes", s.modes as u64),
        ("enrich", s.enrich as u64),
        ("seed", s.seed),
        ("lightfield-positions", i.positions as u64),
        ("lightfield-directions", i.directions as u64),
        ("lightfield-supersamples", i.supersamples as u64),
        ("lightfield-modes", i.lightfield_modes as u64),
        ("response-modes", i.response_modes as u64),
        ("response-rays", i.gather_rays as u64),
        ("interface-seed", i.seed),
        ("prior-lattice", s.prior_lattice as u64),
    ]
}

pub fn section(dictionary: &Dictionary, summary: serde_json::Value) -> Section {
    let mut w = Writer::new(MAGIC);
    let params = parameters(&dictionary.settings, &dictionary.interface);
    let values: Vec<u32> = params.iter().flat_map(|(_, v)| [*v as u32, (*v >> 32) as u32]).collect();
    w.u32s(&values);
    w.u32s(&[dictionary.blocks.len() as u32]);
    for block in &dictionary.blocks {
        w.u32s(&[block.shape.open_mask(), block.samples as u32, block.modes as u32]);
        w.f32s(&block.u_b);
        w.f32s(&block.t_d_b);
        w.f32s(&block.l_imp);
        w.f32s(&block.u_bvol);
    }
    let i = &dictionary.interfaces;
    w.u32s(&[i.lightfield_modes as u32, i.response_modes as u32, i.from_blocks.len() as u32]);
    for (_, _, r) in &i.from_blocks {
        w.f32s(r);
    }
    i.turns.iter().for_each(|t| w.f32s(t));
    w.f32s(&i.u_r);
    w.f32s(&i.t_rlf_r);
    i.u_rvol.iter().for_each(|u| w.f32s(u));
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Nothing, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The name a dictionary made with these parameters is kept under (threads aside): the
/// section's version and the FNV-1a 64 of the parameters as stored, in hex.
pub fn key(settings: &BlockSettings, interface: &InterfaceSettings) -> String {
    let bytes: Vec<u8> = parameters(settings, interface).iter().flat_map(|(_, v)| v.to_le_bytes()).collect();
    format!("v{SECTION_VERSION}-{}", crate::artifact::checksum(&bytes).trim_start_matches("fnv1a64:"))
}

/// The checksum of the dictionary's file, as `read` gives it and a level names it.
pub fn checksum(dictionary: &Dictionary) -> String {
    crate::artifact::checksum(&section(dictionary, serde_json::Value::Null).files[0].1)
}

/// The dictionary of `artifact` with its file's checksum (which a level names); refused when
/// `wanted` is given and it was made with other parameters (threads aside).
pub fn read(artifact: &Artifact, wanted: Option<(&BlockSettings, &InterfaceSettings)>) -> Result<(Dictionary, String), ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, None)?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "MRT dictionary")?;
    let mut stored = [0u64; 16];
    for (i, (name, _)) in parameters(&BlockSettings::default(), &InterfaceSettings::default()).iter().enumerate() {
        stored[i] = r.u32(name)? as u64 | (r.u32(name)? as u64) << 32;
    }
    let (settings, interface) = from_parameters(&stored).map_err(|e| fail(&path, e, REBAKE))?;
    if let Some((block, lightfield)) = wanted {
        let asked = parameters(block, lightfield);
        if let Some(((name, value), had)) = asked.iter().zip(stored).find(|((_, v), had)| v != had) {
            let show = |v: u64| if *name == "light-radius" { f32::from_bits(v as u32).to_string() } else { v.to_string() };
            let problem = format!("the dictionary was made with {name} {}, not the {} asked for", show(had), show(*value));
            return Err(fail(&path, problem, "name a dictionary made with these parameters, or bake without --dictionary to make one"));
        }
    }
    let blocks = read_blocks(&mut r, &settings)?;
    let interfaces = read_interfaces(&mut r, &blocks, &settings, &interface)?;
    r.finish("the interface operators")?;
    let checksum = crate::artifact::checksum(&bin);
    Ok((Dictionary { settings, interface, blocks, interfaces }, checksum))
}

/// The settings of stored `parameters`, refused where no dictionary could have been made so.
fn from_parameters(p: &[u64; 16]) -> Result<(BlockSettings, InterfaceSettings), String> {
    let small = |i: usize, most: u64| (1..=most).contains(&p[i]).then_some(p[i] as usize);
    let bad = |name: &str| format!("stored parameter {name} is impossible");
    let block = BlockSettings {
        samples_per_face: small(0, 64).ok_or_else(|| bad("samples-per-face"))?,
        gather_rays: small(1, 1 << 24).ok_or_else(|| bad("gather-rays"))? as u32,
        prior_grid: small(2, 64).ok_or_else(|| bad("prior-grid"))?,
        prior_lattice: *PriorLattice::ALL.get(p[15] as usize).ok_or_else(|| bad("prior-lattice"))?,
        light_radius: f32::from_bits(p[3] as u32),
        prior_modes: small(4, 1 << 16).ok_or_else(|| bad("prior-modes"))?,
        modes: small(5, 1 << 16).ok_or_else(|| bad("modes"))?,
        enrich: p[6] == 1,
        seed: p[7],
        threads: None,
    };
    let interface = InterfaceSettings {
        positions: small(8, 1024).ok_or_else(|| bad("lightfield-positions"))?,
        directions: small(9, 1024).ok_or_else(|| bad("lightfield-directions"))?,
        supersamples: small(10, 64).ok_or_else(|| bad("lightfield-supersamples"))?,
        lightfield_modes: small(11, 1 << 16).ok_or_else(|| bad("lightfield-modes"))?,
        response_modes: small(12, 1 << 16).ok_or_else(|| bad("response-modes"))?,
        gather_rays: small(13, 1 << 24).ok_or_else(|| bad("response-rays"))? as u32,
        seed: p[14],
    };
    Ok((block, interface))
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| crate::artifact::stored(*v))
}

fn read_blocks(r: &mut Reader, wanted: &BlockSettings) -> Result<Vec<BlockData>, ArtifactError> {
    let path = r.path().to_path_buf();
    let dictionary = Shape::dictionary();
    let count = r.u32("the shape count")? as usize;
    if count != dictionary.len() {
        return Err(fail(&path, format!("{count} shapes where the 2D dictionary has {}", dictionary.len()), REBAKE));
    }
    let mut blocks = Vec::with_capacity(count);
    for expected in dictionary {
        let shape = Shape::from_open_mask(r.u32("a shape's open faces")?).map_err(|e| fail(&path, e, REBAKE))?;
        let (samples, modes) = (r.u32("a shape's sample count")? as usize, r.u32("a shape's mode count")? as usize);
        let own = Samples::new(shape, wanted.samples_per_face).len();
        if shape != expected || samples != own || modes == 0 || modes > wanted.modes.min(samples) {
            let most = wanted.modes.min(own);
            let problem = format!("a shape ({shape:?}, {samples} samples, {modes} modes) is not the dictionary's next ({expected:?}, {own} samples, 1..={most} modes)");
            return Err(fail(&path, problem, REBAKE));
        }
        let size = samples * modes;
        let (u_b, t_d_b, l_imp) = (r.f32s(size, "U_b")?, r.f32s(size, "T_d->b")?, r.f32s(size, "L_imp")?);
        let u_bvol = r.f32s(volume::ROWS * modes, "U_bvol")?;
        if ![&u_b, &t_d_b, &l_imp, &u_bvol].iter().all(|m| finite(m)) {
            return Err(fail(&path, "an operator holds a value that is not finite (or past 1e9)", REBAKE));
        }
        blocks.push(BlockData { shape, samples, modes, u_b, t_d_b, l_imp, u_bvol });
    }
    Ok(blocks)
}

fn read_interfaces(
    r: &mut Reader,
    blocks: &[BlockData],
    wanted: &BlockSettings,
    interface: &InterfaceSettings,
) -> Result<InterfaceData, ArtifactError> {
    let path = r.path().to_path_buf();
    let (k_rlf, k_r, count) =
        (r.u32("the lightfield mode count")? as usize, r.u32("the response mode count")? as usize, r.u32("the interface count")? as usize);
    let slots = slots();
    let n_r = receiver(wanted.samples_per_face).len();
    if k_rlf == 0 || k_rlf > interface.lightfield_modes || k_r == 0 || k_r > interface.response_modes.min(n_r) || count != slots.len() {
        let problem = format!(
            "{k_rlf} lightfield modes, {k_r} response modes and {count} interfaces, where the dictionary has 1..={} , 1..={} and {}",
            interface.lightfield_modes,
            interface.response_modes.min(n_r),
            slots.len()
        );
        return Err(fail(&path, problem, REBAKE));
    }
    let mut from_blocks = Vec::with_capacity(count);
    for (shape, face) in slots {
        from_blocks.push((shape, face, r.f32s(k_rlf * blocks[shape].modes, "R_b->rlf")?));
    }
    let turns = [r.f32s(k_rlf * k_rlf, "R_ahead")?, r.f32s(k_rlf * k_rlf, "R_left")?, r.f32s(k_rlf * k_rlf, "R_right")?];
    let (u_r, t_rlf_r) = (r.f32s(n_r * k_r, "U_r")?, r.f32s(k_r * k_rlf, "T_rlf->r")?);
    let u_rvol = volume::SIDES.iter().map(|_| r.f32s(volume::ROWS * k_r, "U_rvol")).collect::<Result<Vec<_>, _>>()?;
    let all = from_blocks.iter().map(|f| &f.2).chain(&turns).chain([&u_r, &t_rlf_r]).chain(&u_rvol);
    if !all.into_iter().all(|m| finite(m)) {
        return Err(fail(&path, "an interface operator holds a value that is not finite (or past 1e9)", REBAKE));
    }
    Ok(InterfaceData { lightfield_modes: k_rlf, response_modes: k_r, from_blocks, turns, u_r, t_rlf_r, u_rvol })
}

#[cfg(feature = "baking")]
mod built {
    use super::*;
    use crate::mrt::block::{self, BlockOperators};
    use crate::mrt::interface::{self, Interfaces};
    use crate::mrt::level::Turn;
    use crate::shards::Role;
    use nalgebra::DMatrix;

    fn f32s(m: &DMatrix<f64>) -> Vec<f32> {
        m.iter().map(|&v| v as f32).collect()
    }

    fn matrix(rows: usize, columns: usize, values: &[f32]) -> DMatrix<f64> {
        DMatrix::from_iterator(rows, columns, values.iter().map(|&v| v as f64))
    }

    impl Dictionary {
        /// Builds the six shapes' operators, then their interfaces; `stage` is told each
        /// stage's name as it starts, and its error stops the build.
        pub fn build(
            settings: &BlockSettings,
            interface: &InterfaceSettings,
            stage: impl FnMut(&str) -> Result<(), String>,
        ) -> Result<Dictionary, String> {
            Dictionary::build_in_role(settings, interface, None, stage)
        }

        /// As [`Dictionary::build`], in a bake whose `role` in a sharded one (`shards`) is a
        /// plan, a shard or the merge: the six shapes' F are its gathers, each shape reduced
        /// once its F is made or read.
        pub fn build_in_role(
            settings: &BlockSettings,
            interface: &InterfaceSettings,
            role: Option<&Role>,
            mut stage: impl FnMut(&str) -> Result<(), String>,
        ) -> Result<Dictionary, String> {
            let shapes = Shape::dictionary();
            let mut operators: Vec<BlockOperators> = Vec::with_capacity(shapes.len());
            for (i, &shape) in shapes.iter().enumerate() {
                stage(&format!("block shape {} of {}", i + 1, shapes.len()))?;
                let samples = Samples::new(shape, settings.samples_per_face);
                block::gather_shape(shape, &samples, settings, role, i + 1 < shapes.len(), |f| {
                    operators.push(block::reduced(shape, samples.clone(), &f, settings));
                    Ok(())
                })?;
            }
            stage("interfaces")?;
            let built = crate::work::with_threads(settings.threads, || interface::build(&operators, interface));
            Ok(Dictionary::of(settings, interface, &operators, &built))
        }

        /// The stored form of built operators.
        pub fn of(settings: &BlockSettings, interface: &InterfaceSettings, blocks: &[BlockOperators], i: &Interfaces) -> Dictionary {
            let from_blocks = slots()
                .into_iter()
                .map(|(shape, face)| (shape, face, f32s(i.from_block(shape, face).expect("every interface of the dictionary"))))
                .collect();
            let turns = [Turn::Ahead, Turn::Left, Turn::Right].map(|t| f32s(i.turn(t)));
            let interfaces = InterfaceData {
                lightfield_modes: i.t_rlf_r.ncols(),
                response_modes: i.u_r.ncols(),
                from_blocks,
                turns,
                u_r: f32s(&i.u_r),
                t_rlf_r: f32s(&i.t_rlf_r),
                u_rvol: i.u_rvol.iter().map(f32s).collect(),
            };
            let settings = BlockSettings { threads: None, ..settings.clone() };
            Dictionary { settings, interface: interface.clone(), blocks: blocks.iter().map(|b| b.data()).collect(), interfaces }
        }

        /// The operators as the level's traversal takes them (the singular values are not
        /// stored: empty).
        pub fn operators(&self) -> (Vec<BlockOperators>, Interfaces) {
            let grid = self.settings.samples_per_face;
            let blocks: Vec<BlockOperators> = self
                .blocks
                .iter()
                .map(|b| BlockOperators {
                    shape: b.shape,
                    samples: Samples::new(b.shape, grid),
                    u_b: matrix(b.samples, b.modes, &b.u_b),
                    t_d_b: matrix(b.modes, b.samples, &b.t_d_b),
                    l_imp: matrix(b.samples, b.modes, &b.l_imp),
                    u_bvol: matrix(volume::ROWS, b.modes, &b.u_bvol),
                    m_sigma: Vec::new(),
                    prior_sigma: Vec::new(),
                })
                .collect();
            let i = &self.interfaces;
            let k = i.lightfield_modes;
            let from_blocks =
                i.from_blocks.iter().map(|(shape, face, r)| ((*shape, *face), matrix(k, self.blocks[*shape].modes, r))).collect();
            let [ahead, left, right] = &i.turns;
            let turns = [(Turn::Ahead, matrix(k, k, ahead)), (Turn::Left, matrix(k, k, left)), (Turn::Right, matrix(k, k, right))];
            let receiver = receiver(grid);
            let u_r = matrix(receiver.len(), i.response_modes, &i.u_r);
            let t_rlf_r = matrix(i.response_modes, k, &i.t_rlf_r);
            let u_rvol = i.u_rvol.iter().map(|u| matrix(volume::ROWS, i.response_modes, u)).collect();
            (blocks, Interfaces { from_blocks, turns, u_r, t_rlf_r, receiver, u_rvol })
        }
    }
}
