//! Fullsphere irradiance vectors of Michael & Chrysanthou, "Fullsphere Irradiance
//! Factorization" (003): the scene's settings (`extras.relume.fiv`: which meshes are
//! occluders), the occluder types, the artifact sections (`fiv_environment`: DifMap and
//! FIV(Env); `fiv_occluder_<k>`: one FIV table per occluder type) and the run-time formula
//! on the CPU (`occluder_sums.rs`, the oracle of the GPU pass). Behind the `baking` feature,
//! the baker (`baker.rs`).
//!
//! Names: the paper's rho is a distance here (`distance`), its rho_dif the albedo over pi;
//! theta is the azimuth, phi the polar angle, as in its Table 1 grids (spec fiv.md B1-B2).

#[cfg(feature = "baking")]
mod baker;
mod occluder_sums;
mod sections;

#[cfg(feature = "baking")]
pub use baker::*;
#[cfg(feature = "baking")]
mod bake;
#[cfg(feature = "baking")]
pub use bake::*;
pub use occluder_sums::*;
pub use sections::*;

use crate::scene::{Mesh, Scene};
use crate::settings::{as_object, known_keys, SceneBlock};
use glam::Vec3;
use serde_json::Value;

const KEY: &str = "fiv";

/// The scene's `extras.relume.fiv` block: the names of the meshes that occlude; or, for a
/// scene without one, those derived from it (`derived`).
#[derive(Clone, Debug, PartialEq)]
pub struct FivSceneSettings {
    pub occluders: Vec<String>,
    pub derived: bool,
}

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, _| from_block(block).map(|_| ()) };

impl FivSceneSettings {
    /// The scene's block; without one, the occluders derived from the scene: every closed mesh
    /// (it has an inside, as a table's mask needs) whose footprint, the area of its bounds
    /// seen from above, is under 80 % of the scene's (a ground slab or a room around everything
    /// receives light, it does not move over receivers), each name once. Refused when none is.
    pub fn of(scene: &Scene) -> Result<Self, String> {
        match scene.settings.block(KEY) {
            Some(block) => from_block(block),
            None => derive(scene),
        }
    }
}

fn derive(scene: &Scene) -> Result<FivSceneSettings, String> {
    let footprint = |(lo, hi): (Vec3, Vec3)| (hi.x - lo.x) * (hi.z - lo.z);
    let whole = footprint(scene.settings.bounds);
    let mut occluders: Vec<String> = Vec::new();
    for mesh in &scene.meshes {
        let apart = footprint(crate::scene::bounds_of(&mesh.positions)) < 0.8 * whole;
        if apart && not_closed(mesh).is_none() && !occluders.contains(&mesh.name) {
            occluders.push(mesh.name.clone());
        }
    }
    if occluders.is_empty() {
        return Err(format!(
            "the scene names no occluders and none could be derived: none of its {} meshes is closed and under 80 % of its footprint; name the meshes that move over receivers in extras.relume.fiv.occluders",
            scene.meshes.len()
        ));
    }
    Ok(FivSceneSettings { occluders, derived: true })
}

fn from_block(block: &Value) -> Result<FivSceneSettings, String> {
    let o = as_object(block, "extras.relume.fiv")?;
    known_keys(o, "extras.relume.fiv", &["occluders"])?;
    let names = o.get("occluders").and_then(Value::as_array).filter(|a| !a.is_empty());
    let names = names.ok_or("extras.relume.fiv.occluders must be a non-empty array of mesh names")?;
    let occluders: Vec<String> = names
        .iter()
        .map(|n| n.as_str().map(str::to_string).ok_or("extras.relume.fiv.occluders must hold mesh names (strings)"))
        .collect::<Result<_, _>>()?;
    Ok(FivSceneSettings { occluders, derived: false })
}

/// The first dozen of `names` and how many more: a hall of furniture has thousands.
fn first_names<S: AsRef<str>>(names: &[S]) -> String {
    const NAMED: usize = 12;
    let first: Vec<&str> = names.iter().take(NAMED).map(AsRef::as_ref).collect();
    match names.len().saturating_sub(NAMED) {
        0 => first.join(", "),
        more => format!("{} and {more} more", first.join(", ")),
    }
}

/// Occluders of one shape (equal up to a translation) share a type and its table (003 §4:
/// memory grows with types, not instances).
#[derive(Clone, Debug, PartialEq)]
pub struct OccluderType {
    /// The scene's meshes of this shape, the first one the type's representative.
    pub meshes: Vec<usize>,
    /// The bounding radius R.
    pub radius: f32,
}

/// The bounding sphere every FIV formula uses: the centre of the bounds and the largest
/// distance from it (spec fiv.md B3 takes the minimal sphere; this one is exact for the
/// symmetric stand-ins and never smaller than the shape).
pub fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    let (lo, hi) = crate::scene::bounds_of(positions);
    let centre = (lo + hi) * 0.5;
    (centre, positions.iter().map(|p| p.distance(centre)).fold(0.0, f32::max))
}

/// The scene's occluders grouped into types, in the order the scene block names them;
/// refused, by mesh, when a name matches no mesh, is named twice, or its mesh is not closed
/// (an open mesh has no inside, and the table's mask would leak through it).
pub fn occluder_types(scene: &Scene, settings: &FivSceneSettings) -> Result<Vec<OccluderType>, String> {
    let mut types: Vec<OccluderType> = Vec::new();
    for (k, name) in settings.occluders.iter().enumerate() {
        if settings.occluders[..k].contains(name) {
            return Err(format!("extras.relume.fiv.occluders names \"{name}\" twice"));
        }
        let Some(index) = scene.meshes.iter().position(|m| &m.name == name) else {
            let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
            return Err(format!(
                "extras.relume.fiv.occluders names \"{name}\", which is no mesh of the scene (its meshes: {}; a node of several primitives loads as \"<node> primitive <k>\")",
                first_names(&names)
            ));
        };
        let mesh = &scene.meshes[index];
        if let Some(why) = not_closed(mesh) {
            return Err(format!(
                "occluder \"{name}\" is not a closed mesh ({why}); close it or leave it out of extras.relume.fiv.occluders"
            ));
        }
        match types.iter_mut().find(|t| same_shape(&scene.meshes[t.meshes[0]], mesh)) {
            Some(t) => t.meshes.push(index),
            None => types.push(OccluderType { meshes: vec![index], radius: bounding_sphere(&mesh.positions).1 }),
        }
    }
    Ok(types)
}

/// Every occluder of the scene where the scene has it: type by type, each type's meshes in
/// order (the order the technique takes them and moves them by).
pub fn occluders(scene: &Scene, types: &[OccluderType]) -> Vec<Occluder> {
    let instances = types.iter().enumerate().flat_map(|(table, t)| t.meshes.iter().map(move |&m| (table, m)));
    instances.map(|(table, mesh)| Occluder { table, mesh, centre: bounding_sphere(&scene.meshes[mesh].positions).0 }).collect()
}

/// Whether two meshes have the same triangles and the same positions about their centres.
fn same_shape(a: &Mesh, b: &Mesh) -> bool {
    let ((ca, ra), (cb, _)) = (bounding_sphere(&a.positions), bounding_sphere(&b.positions));
    let tolerance = 1e-5 * (1.0 + ra);
    a.indices == b.indices
        && a.positions.len() == b.positions.len()
        && a.positions.iter().zip(&b.positions).all(|(p, q)| ((*p - ca) - (*q - cb)).abs().max_element() <= tolerance)
}

/// Why `mesh` has no inside, or None for a closed mesh: every edge (vertices welded by position)
/// joins an even number of triangles (two on a plain surface, four where closed parts touch
/// along an edge, as a chair's seat and front panel do), and the triangles enclose a volume
/// facing out (a double-sided sheet has even edges and none; FIV's inside test reads the
/// first face a ray meets, which an inside-out mesh turns round).
fn not_closed(mesh: &Mesh) -> Option<String> {
    let key = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let mut edges = std::collections::BTreeMap::new();
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let (ka, kb) = (key(a), key(b));
            *edges.entry(if ka < kb { (ka, kb) } else { (kb, ka) }).or_insert(0u32) += 1;
        }
    }
    let open = edges.values().filter(|&&n| n % 2 == 1).count();
    if open > 0 {
        return Some(format!("{open} edges join an odd number of triangles"));
    }
    let corner = |t: &[u32], k: usize| mesh.positions[t[k] as usize].as_dvec3();
    let volume: f64 = mesh.indices.chunks_exact(3).map(|t| corner(t, 0).dot(corner(t, 1).cross(corner(t, 2))) / 6.0).sum();
    let (lo, hi) = crate::scene::bounds_of(&mesh.positions);
    let bounds = (hi - lo).as_dvec3().element_product();
    // Volumes far below their bounds' are rounding of a shape that encloses none.
    (volume <= ENCLOSED_SHARE * bounds).then(|| {
        format!("its triangles enclose {volume:.3e} m^3 facing out in bounds of {bounds:.3e} m^3: a double-sided sheet, or faces turned in")
    })
}

/// The least share of its bounds' volume a closed mesh encloses.
const ENCLOSED_SHARE: f64 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{closed_box, square, Facing};

    /// `meshes` as one (welded by position only, as a scene's faces are).
    fn joined(meshes: &[Mesh]) -> Mesh {
        let mut out = meshes[0].clone();
        for mesh in &meshes[1..] {
            let first = out.positions.len() as u32;
            out.positions.extend(&mesh.positions);
            out.normals.extend(&mesh.normals);
            out.indices.extend(mesh.indices.iter().map(|i| first + i));
        }
        out
    }

    /// A chair's seat and front panel touch along an edge, which four triangles then share:
    /// the mesh still has an inside. A box without its lid has none, nor has a double-sided
    /// sheet (every edge even) or a box turned inside out.
    #[test]
    fn boxes_that_touch_along_an_edge_are_closed_and_sheets_lidless_or_inverted_boxes_are_not() {
        // Corners of halves and quarters: the shared edge's positions are equal to the bit.
        let seat = closed_box(Vec3::ZERO, Vec3::new(1.0, 0.5, 1.0), 1, Facing::Outward, 0);
        let panel = closed_box(Vec3::new(1.0, 0.5, 0.0), Vec3::new(2.0, 1.0, 1.0), 1, Facing::Outward, 0);
        assert_eq!(not_closed(&seat), None);
        assert_eq!(not_closed(&joined(&[seat.clone(), panel])), None, "boxes sharing an edge (four triangles on it)");
        let mut lidless = seat.clone();
        let lid = |t: &[u32]| t.iter().all(|&i| lidless.normals[i as usize] == Vec3::Y);
        lidless.indices = lidless.indices.chunks_exact(3).filter(|t| !lid(t)).flatten().copied().collect();
        let why = not_closed(&lidless).unwrap();
        assert!(why.starts_with("4 edges join an odd number"), "{why}");
        let mut sheet = square(Vec3::ZERO, Vec3::X, Vec3::Z, 1, 0);
        let turned: Vec<u32> = sheet.indices.chunks_exact(3).flat_map(|t| [t[0], t[2], t[1]]).collect();
        sheet.indices.extend(turned);
        assert!(not_closed(&sheet).unwrap().contains("double-sided sheet"), "{:?}", not_closed(&sheet));
        let inverted = closed_box(Vec3::ZERO, Vec3::new(1.0, 0.5, 1.0), 1, Facing::Inward, 0);
        assert!(not_closed(&inverted).unwrap().contains("faces turned in"), "{:?}", not_closed(&inverted));
    }
}
