//! Modular radiance transfer (Loos et al. 2011, paper 002; ../shared/specs/mrt.md): indirect
//! light for block-structured levels from a dictionary of simple shapes built once for all
//! scenes. This part holds the dictionary's shapes; its section (`dictionary`: the blocks' and
//! the interfaces' operators); the scene's block proxy (`proxy`, `extras.relume.mrt`); a
//! level's blocks (`level`); the scene's geometry mapped onto them with the padded light map
//! (`map`); the level's tables as the run time takes them, with the CPU evaluator the GPU is
//! checked against (`level_data`, section `mrt-level`); and the light volume for dynamic meshes
//! with its CPU evaluator (`volume`: §6.5, §7.3 steps 8-9). Behind `baking`: one block's reduced
//! direct-to-indirect operators (`block`: §4 with the enrichment of App. A), the interface
//! operators between blocks (`interface`: §5.1), T_b->r by traversal and a CPU evaluator on the
//! operators themselves (`evaluate`: §6.3, §7.3), and the level's bake with its solved feedback
//! (`baker`).

#[cfg(feature = "baking")]
mod bake;
#[cfg(feature = "baking")]
pub mod baker;
#[cfg(feature = "baking")]
pub use bake::*;
#[cfg(feature = "baking")]
pub mod block;
#[cfg(feature = "baking")]
pub mod derive;
pub mod dictionary;
#[cfg(feature = "baking")]
pub mod evaluate;
#[cfg(feature = "baking")]
pub mod interface;
#[cfg(feature = "baking")]
mod inverse;
pub mod level;
pub mod level_data;
pub mod map;
pub mod proxy;
#[cfg(feature = "baking")]
pub mod split;
pub mod volume;

pub use proxy::SCENE_BLOCK;
#[cfg(feature = "baking")]
mod svd;
#[cfg(feature = "baking")]
pub use svd::modes_for_energy;

use glam::{Vec2, Vec3};

/// A face of the unit cube [0, 1]^3: the axis it is normal to and the side it lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Face {
    pub axis: usize,
    pub positive: bool,
}

impl Face {
    /// -x, +x, -y, +y, -z, +z.
    pub const ALL: [Face; 6] = [
        Face { axis: 0, positive: false },
        Face { axis: 0, positive: true },
        Face { axis: 1, positive: false },
        Face { axis: 1, positive: true },
        Face { axis: 2, positive: false },
        Face { axis: 2, positive: true },
    ];

    pub fn index(self) -> usize {
        self.axis * 2 + self.positive as usize
    }

    /// "-x", "+x", "-y", "+y", "-z" or "+z", as errors name it.
    pub fn name(self) -> &'static str {
        ["-x", "+x", "-y", "+y", "-z", "+z"][self.index()]
    }

    /// The unit normal pointing into the cube.
    pub fn inward(self) -> Vec3 {
        let mut n = Vec3::ZERO;
        n[self.axis] = if self.positive { -1.0 } else { 1.0 };
        n
    }

    /// The face's other two axes, in increasing order: its (u, v).
    pub fn tangents(self) -> (usize, usize) {
        match self.axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        }
    }

    /// The point of the face at (u, v) in [0, 1]^2.
    pub fn point(self, uv: Vec2) -> Vec3 {
        let (a, b) = self.tangents();
        let mut p = Vec3::ZERO;
        p[self.axis] = self.positive as u32 as f32;
        (p[a], p[b]) = (uv.x, uv.y);
        p
    }

    /// (u, v) of a point on (the plane of) the face.
    pub fn uv(self, p: Vec3) -> Vec2 {
        let (a, b) = self.tangents();
        Vec2::new(p[a], p[b])
    }

    /// The face after `quarter_turns` turns of 90 degrees about +y (x to -z, z to x).
    pub fn turned(self, quarter_turns: u32) -> Face {
        let n = level::turn_direction(-self.inward(), quarter_turns);
        let axis = (0..3).find(|&a| n[a] != 0.0).expect("a unit axis");
        Face { axis, positive: n[axis] > 0.0 }
    }

    /// The face's four corners, in order around it.
    pub fn corners(self) -> [Vec3; 4] {
        [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)].map(|uv| self.point(uv))
    }
}

/// A block of the 2D dictionary: the unit cube with some of its side faces (±x, ±z) open to
/// neighbouring blocks; the top and bottom are always closed (§6.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shape {
    open: [bool; 6],
}

impl Shape {
    pub fn closed() -> Shape {
        Shape { open: [false; 6] }
    }

    /// The cube with `faces` open; refused for the top or bottom (the 2D dictionary has none).
    pub fn with_open(faces: &[Face]) -> Result<Shape, String> {
        let mut shape = Shape::closed();
        for face in faces {
            if face.axis == 1 {
                return Err("a block of the 2D dictionary has its top and bottom closed; open a side face (±x, ±z)".into());
            }
            shape.open[face.index()] = true;
        }
        Ok(shape)
    }

    /// The six shapes of the 2D dictionary, 0 to 4 side faces open up to a turn about +y:
    /// none, one, two adjacent, two opposite, three, four (§6.1: 12 open faces in all).
    pub fn dictionary() -> [Shape; 6] {
        let [nx, px, _, _, nz, pz] = Face::ALL;
        let open = |faces: &[Face]| Shape::with_open(faces).expect("side faces");
        [open(&[]), open(&[nz]), open(&[nz, px]), open(&[nz, pz]), open(&[nz, px, pz]), open(&[nx, px, nz, pz])]
    }

    pub fn is_open(self, face: Face) -> bool {
        self.open[face.index()]
    }

    /// The faces that are there (closed), in `Face::ALL` order.
    pub fn present(self) -> Vec<Face> {
        Face::ALL.into_iter().filter(|f| !self.is_open(*f)).collect()
    }

    pub fn open_faces(self) -> Vec<Face> {
        Face::ALL.into_iter().filter(|f| self.is_open(*f)).collect()
    }

    /// This shape as a dictionary shape turned about +y: (its index in `Shape::dictionary`,
    /// quarter turns q) such that turning that shape's faces by q gives this one's.
    pub fn canonical(self) -> (usize, u32) {
        let dictionary = Shape::dictionary();
        for (i, shape) in dictionary.iter().enumerate() {
            for q in 0..4 {
                let turned: Vec<Face> = shape.open_faces().into_iter().map(|f| f.turned(q)).collect();
                if Shape::with_open(&turned).is_ok_and(|t| t == self) {
                    return (i, q);
                }
            }
        }
        unreachable!("the 2D dictionary holds every side-face shape up to a turn")
    }

    /// Bit `Face::index` set for each open face.
    pub fn open_mask(self) -> u32 {
        Face::ALL.iter().filter(|f| self.is_open(**f)).map(|f| 1 << f.index()).sum()
    }

    /// The shape of `open_mask`; refused for unknown bits and an open top or bottom.
    pub fn from_open_mask(mask: u32) -> Result<Shape, String> {
        if mask >= 1 << 6 {
            return Err(format!("open-face mask {mask} names faces a cube lacks"));
        }
        let faces: Vec<Face> = Face::ALL.into_iter().filter(|f| mask & (1 << f.index()) != 0).collect();
        Shape::with_open(&faces)
    }
}

/// Where the prior's grid^3 sphere lights stand in a block (002 §4.1 says only "uniformly in
/// the volume").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PriorLattice {
    /// At the centres of grid^3 cells: 152 of 216 lights a twelfth of a side from a wall, whose
    /// sharp spots need 74 / 104 / 125 modes for 80 / 90 / 95 % of L_d's energy.
    Centres,
    /// 1 / (grid + 1) apart and as far from the walls: 22 / 41 / 64 modes, Table 2's 22 / 41 / 62.
    Inset,
}

impl PriorLattice {
    pub const ALL: [PriorLattice; 2] = [PriorLattice::Centres, PriorLattice::Inset];

    /// The name the command line gives.
    pub fn name(self) -> &'static str {
        match self {
            PriorLattice::Centres => "centres",
            PriorLattice::Inset => "inset",
        }
    }

    pub fn parse(name: &str) -> Option<PriorLattice> {
        PriorLattice::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The lattice's coordinate `i` of `grid` along an axis, in block sides.
    pub fn coordinate(self, i: usize, grid: usize) -> f32 {
        match self {
            PriorLattice::Centres => (i as f32 + 0.5) / grid as f32,
            PriorLattice::Inset => (i as f32 + 1.0) / (grid + 1) as f32,
        }
    }
}

/// What one block's operators are built from (spec A2 and B3; the paper's values by default).
#[derive(Clone, Debug)]
pub struct BlockSettings {
    /// Samples per face side: 16 (n = 6 x 16^2 for a closed cube).
    pub samples_per_face: usize,
    /// Cosine-weighted gather rays per sample for F: 16,384.
    pub gather_rays: u32,
    /// Sphere lights of the prior per axis, in the block and in each open neighbour: 6.
    pub prior_grid: usize,
    /// Where on each axis the prior's lights stand (docs/BENCHMARKS.md, "The papers' claims").
    pub prior_lattice: PriorLattice,
    /// The prior's sphere lights' radius, in block sides: 0.05.
    pub light_radius: f32,
    /// k_d: prior modes kept: 64.
    pub prior_modes: usize,
    /// k_self (k_b): indirect modes kept: 32.
    pub modes: usize,
    /// App. A: enrich the prior with per-face constants and the first U_b, then rebuild.
    pub enrich: bool,
    pub seed: u64,
    /// Worker threads (None: all); the operators do not depend on it.
    pub threads: Option<usize>,
}

impl Default for BlockSettings {
    fn default() -> Self {
        BlockSettings {
            samples_per_face: 16,
            gather_rays: 16_384,
            prior_grid: 6,
            prior_lattice: PriorLattice::Centres,
            light_radius: 0.05,
            prior_modes: 64,
            modes: 32,
            enrich: true,
            seed: 0,
            threads: None,
        }
    }
}

/// The lightfield's resolution (spec A2: 12^2 positions, 24^2 directions, 5^2 supersamples).
#[derive(Clone, Debug)]
pub struct InterfaceSettings {
    pub positions: usize,
    pub directions: usize,
    pub supersamples: usize,
    /// k_rlf: reduced lightfield modes: 128.
    pub lightfield_modes: usize,
    /// k_r: response modes: 32.
    pub response_modes: usize,
    /// Gather rays per receiving sample for the response G.
    pub gather_rays: u32,
    pub seed: u64,
}

impl Default for InterfaceSettings {
    fn default() -> Self {
        InterfaceSettings {
            positions: 12,
            directions: 24,
            supersamples: 5,
            lightfield_modes: 128,
            response_modes: 32,
            gather_rays: 16_384,
            seed: 0,
        }
    }
}

/// A block's sample points: the texel centres of a `grid` x `grid` raster on each present
/// face, face by face (`Shape::present` order), rows of v, u within (spec B14).
#[derive(Clone, Debug)]
pub struct Samples {
    pub grid: usize,
    pub faces: Vec<Face>,
}

impl Samples {
    pub fn new(shape: Shape, grid: usize) -> Samples {
        Samples { grid, faces: shape.present() }
    }

    /// n: the number of samples.
    pub fn len(&self) -> usize {
        self.faces.len() * self.grid * self.grid
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample `i`'s face, position and inward normal.
    pub fn sample(&self, i: usize) -> (Face, Vec3, Vec3) {
        let per_face = self.grid * self.grid;
        let face = self.faces[i / per_face];
        let (x, y) = (i % per_face % self.grid, i % per_face / self.grid);
        let uv = (Vec2::new(x as f32, y as f32) + 0.5) / self.grid as f32;
        (face, face.point(uv), face.inward())
    }

    /// The samples of face `face` (an index into `faces`) and their bilinear weights at (u, v)
    /// on it: clamped to the outer texel centres (four (sample, weight) pairs, weights summing
    /// to 1).
    pub fn bilinear(&self, face: usize, uv: Vec2) -> [(usize, f32); 4] {
        let g = self.grid;
        let at = |t: f32| {
            let x = (t * g as f32 - 0.5).clamp(0.0, (g - 1) as f32);
            let x0 = (x.floor() as usize).min(g - 1);
            (x0, (x0 + 1).min(g - 1), x - x0 as f32)
        };
        let ((x0, x1, fx), (y0, y1, fy)) = (at(uv.x), at(uv.y));
        let base = face * g * g;
        [
            (base + y0 * g + x0, (1.0 - fx) * (1.0 - fy)),
            (base + y0 * g + x1, fx * (1.0 - fy)),
            (base + y1 * g + x0, (1.0 - fx) * fy),
            (base + y1 * g + x1, fx * fy),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_2d_dictionary_has_six_shapes_and_twelve_open_faces_and_refuses_an_open_top() {
        let shapes = Shape::dictionary();
        assert_eq!(shapes.iter().map(|s| s.open_faces().len()).sum::<usize>(), 12);
        assert!(Shape::with_open(&[Face::ALL[3]]).is_err());
    }

    #[test]
    fn bilinear_reads_reproduce_a_linear_function_between_texel_centres() {
        let samples = Samples::new(Shape::closed(), 5);
        let value = |i: usize| {
            let (face, p, _) = samples.sample(i);
            let uv = face.uv(p);
            1.0 + 2.0 * uv.x - 3.0 * uv.y
        };
        for k in 0..50 {
            let uv = Vec2::new(0.1 + 0.8 * ((k * 7) % 50) as f32 / 50.0, 0.1 + 0.8 * k as f32 / 50.0);
            let read: f32 = samples.bilinear(2, uv).iter().map(|(j, w)| w * value(*j)).sum();
            assert!((read - (1.0 + 2.0 * uv.x - 3.0 * uv.y)).abs() < 1e-5, "{uv}: {read}");
        }
    }

    #[test]
    fn every_side_face_shape_is_a_dictionary_shape_turned() {
        let sides = [Face::ALL[0], Face::ALL[1], Face::ALL[4], Face::ALL[5]];
        for mask in 0..16u32 {
            let open: Vec<Face> = (0..4).filter(|b| mask & (1 << b) != 0).map(|b| sides[b]).collect();
            let shape = Shape::with_open(&open).unwrap();
            let (i, q) = shape.canonical();
            let turned: Vec<Face> = Shape::dictionary()[i].open_faces().into_iter().map(|f| f.turned(q)).collect();
            assert_eq!(Shape::with_open(&turned).unwrap(), shape);
        }
        assert_eq!(Face::ALL[1].turned(1), Face::ALL[4], "+x turns to -z");
        assert_eq!(Face::ALL[3].turned(3), Face::ALL[3], "+y stays");
    }

    #[test]
    fn samples_lie_on_their_faces_and_bilinear_weights_sum_to_one_and_reproduce_a_sample() {
        let samples = Samples::new(Shape::dictionary()[1], 4);
        assert_eq!(samples.len(), 5 * 16);
        for i in 0..samples.len() {
            let (face, p, n) = samples.sample(i);
            assert_eq!(p[face.axis], face.positive as u32 as f32);
            assert_eq!(n, face.inward());
            let f = samples.faces.iter().position(|x| *x == face).unwrap();
            let weights = samples.bilinear(f, face.uv(p));
            assert!((weights.iter().map(|w| w.1).sum::<f32>() - 1.0).abs() < 1e-6);
            let own: f32 = weights.iter().filter(|w| w.0 == i).map(|w| w.1).sum();
            assert!((own - 1.0).abs() < 1e-5, "sample {i} reads itself: {weights:?}");
        }
    }
}
