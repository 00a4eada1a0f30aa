//! The dictionary's section, `mrt-dictionary` (keyed to nothing: made once for every scene):
//! what it was made with and each shape's operators U_b, T_d->b and L_imp (f32, column-major).
//! A level reads it only when it was made with the parameters the level asks for.

use super::{BlockSettings, Shape};
use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};

pub const SECTION: &str = "mrt-dictionary";
pub const SECTION_VERSION: u32 = 1;
const BIN: &str = "mrt-dictionary.bin";
const MAGIC: &[u8; 8] = b"RLMRTD01";

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
}

#[derive(Clone, Debug)]
pub struct Dictionary {
    /// What it was made with (threads aside: they change nothing).
    pub settings: BlockSettings,
    pub blocks: Vec<BlockData>,
}

/// The parameters a dictionary is checked against, as (name, value) in the stored order.
fn parameters(s: &BlockSettings) -> [(&'static str, u64); 8] {
    [
        ("samples-per-face", s.samples_per_face as u64),
        ("gather-rays", s.gather_rays as u64),
        ("prior-grid", s.prior_grid as u64),
        ("light-radius", s.light_radius.to_bits() as u64),
        ("prior-modes", s.prior_modes as u64),
        ("modes", s.modes as u64),
        ("enrich", s.enrich as u64),
        ("seed", s.seed),
    ]
}

pub fn section(dictionary: &Dictionary, summary: serde_json::Value) -> Section {
    let mut w = Writer::new(MAGIC);
    let values: Vec<u32> = parameters(&dictionary.settings).iter().flat_map(|(_, v)| [*v as u32, (*v >> 32) as u32]).collect();
    w.u32s(&values);
    w.u32s(&[dictionary.blocks.len() as u32]);
    for block in &dictionary.blocks {
        w.u32s(&[block.shape.open_mask(), block.samples as u32, block.modes as u32]);
        w.f32s(&block.u_b);
        w.f32s(&block.t_d_b);
        w.f32s(&block.l_imp);
    }
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Nothing, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The dictionary of `artifact`, refused unless it was made with `wanted` (threads aside).
pub fn read(artifact: &Artifact, wanted: &BlockSettings) -> Result<Dictionary, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, None)?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "MRT dictionary")?;
    for (name, value) in parameters(wanted) {
        let stored = r.u32(name)? as u64 | (r.u32(name)? as u64) << 32;
        if stored != value {
            let show = |v: u64| if name == "light-radius" { f32::from_bits(v as u32).to_string() } else { v.to_string() };
            let problem = format!("the dictionary was made with {name} {}, not the {} asked for", show(stored), show(value));
            return Err(fail(&path, problem, "make the dictionary again with the parameters the level asks for"));
        }
    }
    let dictionary = Shape::dictionary();
    let count = r.u32("the shape count")? as usize;
    if count != dictionary.len() {
        return Err(fail(&path, format!("{count} shapes where the 2D dictionary has {}", dictionary.len()), REBAKE));
    }
    let mut blocks = Vec::with_capacity(count);
    for expected in dictionary {
        let shape = Shape::from_open_mask(r.u32("a shape's open faces")?).map_err(|e| fail(&path, e, REBAKE))?;
        let (samples, modes) = (r.u32("a shape's sample count")? as usize, r.u32("a shape's mode count")? as usize);
        let own = super::Samples::new(shape, wanted.samples_per_face).len();
        if shape != expected || samples != own || modes == 0 || modes > wanted.modes.min(samples) {
            let most = wanted.modes.min(own);
            let problem = format!("a shape ({shape:?}, {samples} samples, {modes} modes) is not the dictionary's next ({expected:?}, {own} samples, 1..={most} modes)");
            return Err(fail(&path, problem, REBAKE));
        }
        let size = samples * modes;
        let (u_b, t_d_b, l_imp) = (r.f32s(size, "U_b")?, r.f32s(size, "T_d->b")?, r.f32s(size, "L_imp")?);
        if [&u_b, &t_d_b, &l_imp].iter().any(|m| m.iter().any(|v| !v.is_finite())) {
            return Err(fail(&path, "an operator holds a value that is not finite", REBAKE));
        }
        blocks.push(BlockData { shape, samples, modes, u_b, t_d_b, l_imp });
    }
    r.finish("the last shape")?;
    Ok(Dictionary { settings: BlockSettings { threads: None, ..wanted.clone() }, blocks })
}
