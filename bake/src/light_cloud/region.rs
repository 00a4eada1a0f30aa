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
/// inside closed geometry (it reaches nothing), and when the scene has no light.
pub fn reachable(scene: &Scene, bvh: &SceneBvh) -> Result<Reachable, String> {
    let (lo, hi) = scene.settings.bounds;
    let voxel = ((hi - lo).max_element() / VOXELS).max(1e-6);
    let counts = ((hi - lo) / voxel).ceil().as_ivec3().max(IVec3::ONE);
    let centre = |v: IVec3| lo + (v.as_vec3() + 0.5) * voxel;
    let index = |v: IVec3| (v.x + counts.x * (v.y + counts.y * v.z)) as usize;
    let total = (counts.x * counts.y * counts.z) as usize;
    let mut reached = vec![false; total];
    let mut free: Vec<Option<bool>> = vec![None; total];
    let mut is_free = |v: IVec3| *free[index(v)].get_or_insert_with(|| !inside(bvh, centre(v)));
    let mut queue = Vec::new();
    if scene.lights.is_empty() {
        return Err("the scene has no point or spot light to derive the cloud's region from; declare extras.relume.light_cloud.grid".into());
    }
    for light in &scene.lights {
        let v = ((light.position - lo) / voxel).floor().as_ivec3().clamp(IVec3::ZERO, counts - 1);
        if inside(bvh, light.position) || !is_free(v) {
            return Err(format!(
                "light \"{}\" at {} stands inside closed geometry: no free space reaches it, so the cloud's region cannot be derived from it; move the light or declare extras.relume.light_cloud.grid",
                light.name, light.position
            ));
        }
        if !reached[index(v)] {
            reached[index(v)] = true;
            queue.push(v);
        }
    }
    let steps = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];
    while let Some(v) = queue.pop() {
        for step in steps {
            let n = v + step;
            if n.cmplt(IVec3::ZERO).any() || n.cmpge(counts).any() || reached[index(n)] {
                continue;
            }
            if is_free(n) && bvh.visible(centre(v), centre(n)) {
                reached[index(n)] = true;
                queue.push(n);
            }
        }
    }
    let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for z in 0..counts.z {
        for y in 0..counts.y {
            for x in 0..counts.x {
                let v = IVec3::new(x, y, z);
                if reached[index(v)] {
                    min = min.min(lo + v.as_vec3() * voxel);
                    max = max.max(lo + (v.as_vec3() + 1.0) * voxel);
                }
            }
        }
    }
    let (min, max) = (min.max(lo), max.min(hi));
    let cell = ((max - min).element_product() / CELLS).cbrt().max(1e-6);
    let mut grid_counts = ((max - min) / cell).round().as_uvec3().max(glam::UVec3::ONE).to_array();
    while grid_counts.iter().product::<u32>() > MAX_CLOUD_LIGHTS {
        grid_counts = grid_counts.map(|c| (c * 3 / 4).max(1));
    }
    let count = reached.iter().filter(|&&r| r).count();
    Ok(Reachable { grid: CloudGrid { min, max, counts: grid_counts }, reached: count, voxels: total })
}
