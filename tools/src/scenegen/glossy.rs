//! 004's glossy scene (Table 1's Bunny: 15k triangles, 64 cloud lights, n_b = 16, CPCA without
//! light clustering; its Fig. 9): a lumpy blob of 20,480 triangles (smooth: shared vertices)
//! with the normalised modified Phong lobe of exponent 12, standing in a closed room between a
//! red and a blue wall, every wall a welded grid.

use super::geometry::blob;
use super::gltf_writer::Builder;
use super::scenes::exposure_one_intensity;
use super::settings::GLOSSY_SETTINGS;
use glam::DVec3;

pub(super) fn glossy_enclosure() -> Builder {
    let mut b = Builder::new(GLOSSY_SETTINGS);
    let white = b.material("white", [0.7, 0.7, 0.7]);
    let red = b.material("red", [0.65, 0.08, 0.06]);
    let blue = b.material("blue", [0.08, 0.15, 0.6]);
    // rho_d + rho_s = 0.8: a grey blob with a broad highlight (the paper's Phong exponent 12).
    let glossy = b.phong_material("glossy", [0.5, 0.5, 0.5], 0.3, 12.0);
    let (lo, hi) = (DVec3::new(-0.6, 0.0, -0.6), DVec3::new(0.6, 1.0, 0.6));
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let walls = [
        ("Floor", white, [p(lo.x, lo.y, lo.z), p(hi.x, lo.y, lo.z), p(hi.x, lo.y, hi.z), p(lo.x, lo.y, hi.z)]),
        ("Ceiling", white, [p(lo.x, hi.y, lo.z), p(lo.x, hi.y, hi.z), p(hi.x, hi.y, hi.z), p(hi.x, hi.y, lo.z)]),
        ("BackWall", white, [p(lo.x, lo.y, lo.z), p(lo.x, hi.y, lo.z), p(hi.x, hi.y, lo.z), p(hi.x, lo.y, lo.z)]),
        ("FrontWall", white, [p(lo.x, lo.y, hi.z), p(hi.x, lo.y, hi.z), p(hi.x, hi.y, hi.z), p(lo.x, hi.y, hi.z)]),
        ("RedWall", red, [p(lo.x, lo.y, lo.z), p(lo.x, lo.y, hi.z), p(lo.x, hi.y, hi.z), p(lo.x, hi.y, lo.z)]),
        ("BlueWall", blue, [p(hi.x, lo.y, lo.z), p(hi.x, hi.y, lo.z), p(hi.x, hi.y, hi.z), p(hi.x, lo.y, hi.z)]),
    ];
    let centre = (lo + hi) / 2.0;
    for (name, material, quad) in walls {
        let mesh = b.grid_mesh(name, &[quad], 10, |c| centre - c, material);
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }
    let mesh = b.smooth_mesh("Blob", &blob(0.18, 5), glossy);
    b.mesh_node("Blob", mesh, DVec3::new(0.0, 0.22, 0.0), DVec3::ONE);
    let light_position = DVec3::new(0.3, 0.75, 0.25);
    b.point_light("RoomPoint", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y));
    // 4 x 4 x 4 over the room; those inside the blob are dropped at bake time.
    b.light_cloud_grid(lo, hi, [4, 4, 4]);
    b.camera("RoomCamera", DVec3::new(0.05, 0.6, 0.57), DVec3::new(0.0, 0.2, -0.1), 70f64.to_radians(), Some(1.0), 0.02, 5.0);
    b
}
