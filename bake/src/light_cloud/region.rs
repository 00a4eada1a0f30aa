//! The cloud's grid derived from a scene that declares none: over the space the scene's lights
//! can reach, not the scene's whole box (a model's walls, its furniture, the ground under it
//! and the space outside a building would hold most of a box's cloud lights, which stand for no
//! light a user can place). A 24-voxel grid along the scene's longest side is flooded from
//! each light's voxel through voxels whose middles are not inside closed geometry, neighbour
//! to neighbour where nothing blocks the segment between their middles; the cloud's box is the
//! reached voxels' bounds, its cells as near cubes as about 216 of them (004's Cornell cloud)
//! allow.

use super::baker::inside;
use super::{CloudGrid, MAX_CLOUD_LIGHTS};
use crate::bvh::SceneBvh;
use crate::scene::Scene;
use glam::{IVec3, Vec3};

/// Voxels along the scene's longest side.
const VOXELS: f32 = 24.0;

/// About this many cloud lights in the derived grid (004 Table 1's Cornell box: 6^3).
const CELLS: f32 = 216.0;

/// A derived grid and how much of the scene's box the lights reach.
#[derive(Clone, Debug, PartialEq)]
pub struct Reachable {
    pub grid: CloudGrid,
    pub reached: usize,
    pub voxels: usize,
}

/// The grid over the space `scene`'s lights reach; refused, naming the light, when one stands
/// inside closed geometry (it reaches nothing), and when the scene has no light. The flood runs
/// twice: over the scene's bounds, then over what that reached widened by a voxel, so a room
/// in a large model (a house on its terrain) is resolved as finely as a room alone.
pub fn reachable(scene: &Scene, bvh: &SceneBvh) -> Result<Reachable, String> {
    if scene.local_lights().next().is_none() {
        return Err("the scene has no point or spot light to derive the cloud's region from; declare extras.relume.light_cloud.grid".into());
    }
    // The scene's bounds and its lights (a spot above a model lights it from outside them).
    let (lo, hi) = scene.local_lights().fold(scene.settings.bounds, |(lo, hi), l| (lo.min(l.position), hi.max(l.position)));
    let coarse = flood(scene, bvh, lo, hi)?;
    let widen = coarse.voxel;
    let fine = flood(scene, bvh, (coarse.min - widen).max(lo), (coarse.max + widen).min(hi))?;
    let (min, max) = (fine.min, fine.max);
    let cell = ((max - min).element_product() / CELLS).cbrt().max(1e-6);
    let mut counts = ((max - min) / cell).round().as_uvec3().max(glam::UVec3::ONE).to_array();
    while counts.iter().product::<u32>() > MAX_CLOUD_LIGHTS {
        counts = counts.map(|c| (c * 3 / 4).max(1));
    }
    Ok(Reachable { grid: CloudGrid { min, max, counts }, reached: fine.reached, voxels: fine.voxels })
}

/// What one flood over a box reached: its voxels' bounds and count, of how many, of what size.
struct Flood {
    min: Vec3,
    max: Vec3,
    reached: usize,
    voxels: usize,
    voxel: f32,
}

/// Floods `VOXELS` voxels along the longest side of `lo`..`hi` from every light's voxel.
fn flood(scene: &Scene, bvh: &SceneBvh, lo: Vec3, hi: Vec3) -> Result<Flood, String> {
    let voxel = ((hi - lo).max_element() / VOXELS).max(1e-6);
    let counts = ((hi - lo) / voxel).ceil().as_ivec3().max(IVec3::ONE);
    let centre = |v: IVec3| lo + (v.as_vec3() + 0.5) * voxel;
    let index = |v: IVec3| (v.x + counts.x * (v.y + counts.y * v.z)) as usize;
    let total = (counts.x * counts.y * counts.z) as usize;
    let mut reached = vec![false; total];
    let mut free: Vec<Option<bool>> = vec![None; total];
    let mut is_free = |v: IVec3| *free[index(v)].get_or_insert_with(|| !inside(bvh, centre(v)));
    let mut queue = Vec::new();
    // Segments start at a voxel's middle, or at the light in a light's voxel (whose middle may
    // be inside something: a lamp by a wall).
    let mut seeds: Vec<(IVec3, Vec3)> = Vec::new();
    for light in scene.local_lights() {
        let v = ((light.position - lo) / voxel).floor().as_ivec3().clamp(IVec3::ZERO, counts - 1);
        if inside(bvh, light.position) {
            return Err(format!(
                "light \"{}\" at {} stands inside closed geometry: no free space reaches it, so the cloud's region cannot be derived from it; move the light or declare extras.relume.light_cloud.grid",
                light.name, light.position
            ));
        }
        if !reached[index(v)] {
            reached[index(v)] = true;
            queue.push(v);
            seeds.push((v, light.position));
        }
    }
    let start = |v: IVec3| seeds.iter().find(|(s, _)| *s == v).map_or(centre(v), |(_, p)| *p);
    let steps = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];
    while let Some(v) = queue.pop() {
        for step in steps {
            let n = v + step;
            if n.cmplt(IVec3::ZERO).any() || n.cmpge(counts).any() || reached[index(n)] {
                continue;
            }
            if is_free(n) && bvh.visible(start(v), centre(n)) {
                reached[index(n)] = true;
                queue.push(n);
            }
        }
    }
    let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (i, _) in reached.iter().enumerate().filter(|(_, r)| **r) {
        let v = IVec3::new(i as i32 % counts.x, (i as i32 / counts.x) % counts.y, i as i32 / (counts.x * counts.y));
        min = min.min(lo + v.as_vec3() * voxel);
        max = max.max(lo + (v.as_vec3() + 1.0) * voxel);
    }
    let count = reached.iter().filter(|&&r| r).count();
    Ok(Flood { min: min.max(lo), max: max.min(hi), reached: count, voxels: total, voxel })
}
