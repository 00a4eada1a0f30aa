//! The scenes, each from its stated source: geometry, materials, lights, camera, settings.

use super::geometry::*;
use super::gltf_writer::Builder;
use super::settings::*;
use glam::DVec3;

/// Cornell data (millimetres, y up, camera at z = -800 looking towards +z) to glTF metres.
///
/// The Cornell data is itself right-handed: seen from its camera, +x points left, which is
/// why the red wall (x ≈ 556) is on the left in the classic images. Negating z alone would
/// mirror the box (red on the right), so both x and z are negated — a half turn about Y,
/// which keeps handedness and winding — and x is shifted so the box is centred on x = 0.
/// Result: the open front at z = 0, the back wall at z = -0.5592, the camera on +Z looking
/// down -Z (glTF's camera axis) with no rotation at all.
pub(super) fn cornell_point(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new((278.0 - x) * 0.001, y * 0.001, -z * 0.001)
}

/// The Cornell box scene: [`cornell_box`] with the published area light (130 x 105 mm at
/// the ceiling centre) turned into a spot light 1 cm under the ceiling pointing down, inner
/// cone 60 degrees, outer 70: it lights the floor, the blocks and the lower walls directly
/// and leaves the ceiling to indirect light, roughly as the area light does.
pub(super) fn cornell() -> Builder {
    let mut b = Builder::new(CORNELL_SETTINGS);
    cornell_box(&mut b, None, None);
    // Under the centre of the published light (x 213..343, z 227..332), 1 cm below the ceiling.
    let light_position = cornell_point(278.0, 538.8, 279.5);
    b.spot_light("CeilingSpot", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y), 60.0, 70.0);
    cornell_camera(&mut b);
    b
}

/// Fig. 9 of Iones et al. (2003): the Cornell box lit by a spot light 5 cm in front of the
/// red wall at mid height and mid depth, pointing at the wall, cones 40 and 50 degrees, so
/// its light leaves only a spot about 12 cm wide on the wall and everything else is lit by
/// light that bounced off that spot. Obscurance's indirect term follows each light's own
/// unshadowed irradiance, which is zero outside the cone: the method's worst case, and a
/// test that a bake which claims to do better really does.
///
/// The aim point is the middle of the wall quad's diagonal, which both of its triangles
/// contain, and the light sits on the mean of their normals (they differ by half a degree:
/// the published wall is not quite planar), so the wall straight in front is exactly
/// 5 cm away. So close, the light emits about 1/230 of the power of `cornell`'s (0.0136
/// against 3.17 W), and the red wall passes on 63% of its red and 5 to 7% of its green
/// and blue: views of the room need a far higher exposure than 1.
pub(super) fn cornell_wall_light() -> Builder {
    let mut b = Builder::new(CORNELL_WALL_LIGHT_SETTINGS);
    cornell_box(&mut b, None, None);
    let wall = CORNELL_RED_WALL.map(|v| cornell_point(v[0], v[1], v[2]));
    let centre = cornell_room_centre();
    let inward = quad_facing(wall, |c| centre - c).iter().map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize()).sum::<DVec3>().normalize();
    let aim = (wall[0] + wall[2]) * 0.5;
    let distance = 0.05;
    b.spot_light("WallSpot", aim + distance * inward, -inward, exposure_one_intensity(distance), 40.0, 50.0);
    cornell_camera(&mut b);
    b
}

/// 004's Cornell scene (Table 1: about 4k triangles, a 6 x 6 x 6 cloud): the Cornell box with
/// each face a 12 x 12 grid of welded vertices (4,320 triangles), so the per-vertex transfer
/// has vertices across every surface, lit by one point light 15 cm under the ceiling's centre
/// (pi lux on the floor below it). The cloud's grid spans the room; its cells inside the
/// blocks are dropped at bake time.
pub(super) fn cornell_cloud() -> Builder {
    let mut b = Builder::new(CORNELL_SETTINGS);
    cornell_box(&mut b, Some(12), None);
    let light_position = cornell_point(278.0, 398.8, 279.5);
    b.point_light("CentrePoint", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y));
    // The room's box: x from the red wall's 556 mm to the green wall's 0, floor to ceiling,
    // the open front to the back wall.
    b.light_cloud_grid(cornell_point(556.0, 0.0, 559.2), cornell_point(0.0, 548.8, 0.0), [6, 6, 6]);
    cornell_camera(&mut b);
    b
}

/// 004's Window scene (Table 1: about 5k triangles, 250 lights inside and out): `cornell-cloud`
/// with a window about 15 cm square in the back wall, high enough for a light to pass over the
/// tall block, the wall 2 cm thick, and behind it a closed yard 40 cm deep. One point light in
/// the room in front of the window; the cloud's 5 x 5 x 10 grid spans room and yard, so a
/// light carried in through the window crosses from cloud lights the room's vertices see only
/// through the window to those inside: the paper's Fig. 7 popping case.
pub(super) fn cornell_window() -> Builder {
    let mut b = Builder::new(CORNELL_SETTINGS);
    let window = Hole { s: [0.365, 0.635], t: [0.63, 0.9] };
    let white = cornell_box(&mut b, Some(12), Some(&window));
    let p = |v: [f64; 3]| cornell_point(v[0], v[1], v[2]);
    let back_wall = CORNELL_BACK_WALL.map(p);
    let thickness = cornell_point(0.0, 0.0, 20.0) - cornell_point(0.0, 0.0, 0.0);
    let outer = back_wall.map(|c| c + thickness);
    let mesh = b.grid_mesh("BackWallOutside", &window.around(outer), 4, |_| thickness, white);
    b.mesh_node("BackWallOutside", mesh, DVec3::ZERO, DVec3::ONE);
    let [a, c, d, e] = window.corners(back_wall);
    let axis = (a + d) * 0.5;
    let jambs = [[a, c], [c, d], [d, e], [e, a]].map(|[from, to]| [from, to, to + thickness, from + thickness]);
    let mesh =
        b.grid_mesh("WindowJambs", &jambs, 1, |x| axis + thickness * ((x - axis).dot(thickness) / thickness.length_squared()) - x, white);
    b.mesh_node("WindowJambs", mesh, DVec3::ZERO, DVec3::ONE);
    // The yard: x and y as the room's box, from the wall's outside 40 cm back.
    let (x, y, z) = ([556.0, 0.0], [0.0, 548.8], [579.2, 979.2]);
    let yard = [
        [[x[0], y[0], z[0]], [x[1], y[0], z[0]], [x[1], y[0], z[1]], [x[0], y[0], z[1]]],
        [[x[0], y[1], z[0]], [x[0], y[1], z[1]], [x[1], y[1], z[1]], [x[1], y[1], z[0]]],
        [[x[0], y[0], z[1]], [x[1], y[0], z[1]], [x[1], y[1], z[1]], [x[0], y[1], z[1]]],
        [[x[0], y[0], z[0]], [x[0], y[0], z[1]], [x[0], y[1], z[1]], [x[0], y[1], z[0]]],
        [[x[1], y[0], z[0]], [x[1], y[1], z[0]], [x[1], y[1], z[1]], [x[1], y[0], z[1]]],
    ];
    let yard_centre = p([278.0, 274.4, 779.2]);
    let mesh = b.grid_mesh("Yard", &yard.map(|q| q.map(p)), 6, |c| yard_centre - c, white);
    b.mesh_node("Yard", mesh, DVec3::ZERO, DVec3::ONE);
    let light_position = p([278.0, 450.0, 300.0]);
    b.point_light("RoomPoint", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y));
    // Cells 98 mm deep with a border in the wall's middle: the nearest cloud lights stand 39 mm
    // either side of it (a light centimetres from a wall would outshine the rest: reduce.rs).
    b.light_cloud_grid(p([556.0, 0.0, 961.2]), p([0.0, 548.8, -18.8]), [5, 5, 10]);
    cornell_camera(&mut b);
    b
}

/// A hole in a quad, in the quad's parameters: s from its first corner to its second, t from
/// its first to its fourth.
pub(super) struct Hole {
    s: [f64; 2],
    t: [f64; 2],
}

impl Hole {
    fn at(q: &[DVec3; 4], s: f64, t: f64) -> DVec3 {
        (q[0] * (1.0 - s) + q[1] * s) * (1.0 - t) + (q[3] * (1.0 - s) + q[2] * s) * t
    }

    /// The hole's corners in `q`, in the quad's own order.
    fn corners(&self, q: [DVec3; 4]) -> [DVec3; 4] {
        let ([s0, s1], [t0, t1]) = (self.s, self.t);
        [Hole::at(&q, s0, t0), Hole::at(&q, s1, t0), Hole::at(&q, s1, t1), Hole::at(&q, s0, t1)]
    }

    /// `q` less the hole: four quads (below, above, and either side of it).
    fn around(&self, q: [DVec3; 4]) -> [[DVec3; 4]; 4] {
        let ([s0, s1], [t0, t1]) = (self.s, self.t);
        [[0.0, 1.0, 0.0, t0], [0.0, 1.0, t1, 1.0], [0.0, s0, t0, t1], [s1, 1.0, t0, t1]]
            .map(|[sa, sb, ta, tb]| [Hole::at(&q, sa, ta), Hole::at(&q, sb, ta), Hole::at(&q, sb, tb), Hole::at(&q, sa, tb)])
    }
}

/// The back wall's corners (Cornell millimetres).
const CORNELL_BACK_WALL: [[f64; 3]; 4] = [[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8, 559.2]];

/// The red wall's corners (Cornell millimetres), named because `cornell-wall-light` aims at it.
pub(super) const CORNELL_RED_WALL: [[f64; 3]; 4] = [[552.8, 0.0, 0.0], [549.6, 0.0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0.0]];

/// The middle of the Cornell room's floor-to-ceiling, wall-to-wall box, in glTF metres.
pub(super) fn cornell_room_centre() -> DVec3 {
    cornell_point(278.0, 274.4, 279.6)
}

/// The Cornell box, vertex for vertex from "Cornell Box data"
/// (<https://www.graphics.cornell.edu/online/box/data.html>): floor, ceiling, back wall,
/// red left wall, green right wall, and the short and tall blocks (five faces each: the
/// published data has no bottom faces, the blocks stand on the floor). Albedos are the
/// usual linear-RGB fits to the published reflectance spectra. Flat-shaded quads, or with
/// `grid` n, each face an n x n grid of welded vertices ([`Builder::grid_mesh`]); with `window`
/// (grids only), the back wall has that hole. Returns the white material.
pub(super) fn cornell_box(b: &mut Builder, grid: Option<u32>, window: Option<&Hole>) -> usize {
    let white = b.material("white", [0.725, 0.71, 0.68]);
    let red = b.material("red", [0.63, 0.065, 0.05]);
    let green = b.material("green", [0.14, 0.45, 0.091]);
    let p = |v: [f64; 3]| cornell_point(v[0], v[1], v[2]);

    let room_centre = cornell_room_centre();
    let room: [(&str, usize, [[f64; 3]; 4]); 5] = [
        ("Floor", white, [[552.8, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 559.2], [549.6, 0.0, 559.2]]),
        ("Ceiling", white, [[556.0, 548.8, 0.0], [556.0, 548.8, 559.2], [0.0, 548.8, 559.2], [0.0, 548.8, 0.0]]),
        ("BackWall", white, CORNELL_BACK_WALL),
        ("RightWall", green, [[0.0, 0.0, 559.2], [0.0, 0.0, 0.0], [0.0, 548.8, 0.0], [0.0, 548.8, 559.2]]),
        ("LeftWall", red, CORNELL_RED_WALL),
    ];
    for (name, material, quad) in room {
        // Room surfaces face into the room.
        let mesh = match grid {
            None => b.mesh(name, &quad_facing(quad.map(p), |c| room_centre - c), material),
            Some(n) => match window.filter(|_| name == "BackWall") {
                Some(hole) => b.grid_mesh(name, &hole.around(quad.map(p)), n, |c| room_centre - c, material),
                None => b.grid_mesh(name, &[quad.map(p)], n, |c| room_centre - c, material),
            },
        };
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }

    let short_block: [[[f64; 3]; 4]; 5] = [
        [[130.0, 165.0, 65.0], [82.0, 165.0, 225.0], [240.0, 165.0, 272.0], [290.0, 165.0, 114.0]],
        [[290.0, 0.0, 114.0], [290.0, 165.0, 114.0], [240.0, 165.0, 272.0], [240.0, 0.0, 272.0]],
        [[130.0, 0.0, 65.0], [130.0, 165.0, 65.0], [290.0, 165.0, 114.0], [290.0, 0.0, 114.0]],
        [[82.0, 0.0, 225.0], [82.0, 165.0, 225.0], [130.0, 165.0, 65.0], [130.0, 0.0, 65.0]],
        [[240.0, 0.0, 272.0], [240.0, 165.0, 272.0], [82.0, 165.0, 225.0], [82.0, 0.0, 225.0]],
    ];
    let tall_block: [[[f64; 3]; 4]; 5] = [
        [[423.0, 330.0, 247.0], [265.0, 330.0, 296.0], [314.0, 330.0, 456.0], [472.0, 330.0, 406.0]],
        [[423.0, 0.0, 247.0], [423.0, 330.0, 247.0], [472.0, 330.0, 406.0], [472.0, 0.0, 406.0]],
        [[472.0, 0.0, 406.0], [472.0, 330.0, 406.0], [314.0, 330.0, 456.0], [314.0, 0.0, 456.0]],
        [[314.0, 0.0, 456.0], [314.0, 330.0, 456.0], [265.0, 330.0, 296.0], [265.0, 0.0, 296.0]],
        [[265.0, 0.0, 296.0], [265.0, 330.0, 296.0], [423.0, 330.0, 247.0], [423.0, 0.0, 247.0]],
    ];
    for (name, faces) in [("ShortBlock", short_block), ("TallBlock", tall_block)] {
        let corners: Vec<DVec3> = faces.iter().flatten().map(|&v| p(v)).collect();
        let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
        // Block faces face away from the block.
        let mesh = match grid {
            None => b.mesh(name, &faces.iter().flat_map(|q| quad_facing(q.map(p), |c| c - centre)).collect::<Vec<_>>(), white),
            Some(n) => b.grid_mesh(name, &faces.map(|q| q.map(p)), n, |c| c - centre, white),
        };
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }
    white
}

/// The published camera: (278, 273, -800) looking along +z with a 35 mm lens on a
/// 25 x 25 mm film, i.e. yfov = 2 atan(12.5 / 35) ≈ 39.3 degrees, square.
pub(super) fn cornell_camera(b: &mut Builder) {
    let yfov = 2.0 * (12.5f64 / 35.0).atan();
    let eye = cornell_point(278.0, 273.0, -800.0);
    b.camera("CornellCamera", eye, eye + DVec3::NEG_Z, yfov, Some(1.0), 0.1, 3.0);
}

/// Intensity (cd) of a light `distance` metres from the surface straight in front of it
/// (the floor below a light pointing down) that gives that surface an irradiance of pi lux,
/// so a Lambertian surface there has radiance equal to its albedo: exposure 1 shows it
/// mid-range without clipping, whatever the light's distance.
pub(super) fn exposure_one_intensity(distance: f64) -> f64 {
    std::f64::consts::PI * distance * distance
}

/// The ground shared by the occluder scenes: a 4 x 4 m quad at y = 0 facing up.
pub(super) fn ground(b: &mut Builder) {
    ground_of_half_size(b, 2.0);
}

/// A ground quad 2h x 2h at y = 0 facing up, centred on the origin.
pub(super) fn ground_of_half_size(b: &mut Builder, h: f64) {
    let grey = b.material("ground", [0.8, 0.8, 0.8]);
    let quad = [DVec3::new(-h, 0.0, -h), DVec3::new(h, 0.0, -h), DVec3::new(h, 0.0, h), DVec3::new(-h, 0.0, h)];
    let mesh = b.mesh("Ground", &quad_facing(quad, |_| DVec3::Y), grey);
    b.mesh_node("Ground", mesh, DVec3::ZERO, DVec3::ONE);
}

/// The occluder scenes' light and camera: a spot 3 m over the origin pointing down (outer
/// cone 45 degrees, so the whole plane but its corners is lit), and a camera in front and
/// to the side, 27 degrees above the horizon, low enough to see the floor under the
/// occluders and high enough to see their shadow around them.
pub(super) fn occluder_light_and_camera(b: &mut Builder) {
    let light_position = DVec3::new(0.0, 3.0, 0.0);
    b.spot_light("Spot", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y), 35.0, 45.0);
    b.camera("Camera", DVec3::new(2.0, 3.0, 4.5), DVec3::new(0.0, 0.5, 0.0), 45f64.to_radians(), None, 0.1, 20.0);
}

/// A 0.5 m cube whose bottom is 0.75 m above the ground, centred under the light.
pub(super) fn occluder_plane() -> Builder {
    let mut b = Builder::new(OCCLUDER_SETTINGS);
    ground(&mut b);
    let blue = b.material("occluder", [0.2, 0.35, 0.7]);
    let cube = b.mesh("Cube", &unit_cube(), blue);
    b.mesh_node("Box", cube, DVec3::new(0.0, 1.0, 0.0), DVec3::splat(0.5));
    occluder_light_and_camera(&mut b);
    b
}

/// A small plate (0.4 x 0.05 x 0.4 m) at 1.6 m over a bigger one (1 x 0.05 x 1 m) at 0.8 m,
/// both centred under the light: on the floor the small plate's shadow (about 0.87 m wide)
/// lies inside the big plate's (about 1.35 m), which is where a variance shadow map leaks
/// light, since the depth distribution there has two far-apart occluder depths.
pub(super) fn occluder_stacked() -> Builder {
    let mut b = Builder::new(OCCLUDER_SETTINGS);
    ground(&mut b);
    let blue = b.material("occluder", [0.2, 0.35, 0.7]);
    let cube = b.mesh("Cube", &unit_cube(), blue);
    b.mesh_node("UpperPlate", cube, DVec3::new(0.0, 1.6, 0.0), DVec3::new(0.4, 0.05, 0.4));
    b.mesh_node("LowerPlate", cube, DVec3::new(0.0, 0.8, 0.0), DVec3::new(1.0, 0.05, 1.0));
    occluder_light_and_camera(&mut b);
    b
}

/// A stand-in for the obscurance paper's Table 1 scene (Iones et al. 2003) of its size,
/// 180 triangles, not a copy of the paper's model. A 4 x 3 x 4 m room (each surface a
/// 2 x 2 grid, 48 triangles), a table of five boxes and a chair of six (12 triangles each)
/// pushed 10 cm under it: the small gaps obscurance is about (seat under table top, legs
/// on the floor, furniture near nothing but the floor) next to large open surfaces.
///
/// Light: a spot 5 cm under the ceiling over free floor beside the furniture, so the floor
/// straight below it gets pi lux, pointing down with cones 45 and 60 degrees: the whole
/// floor and the lower walls directly, the ceiling only by bounces. Camera: at eye height
/// in the front-left corner, looking at the furniture, so the back and right walls frame it.
pub(super) fn table_chair() -> Builder {
    let mut b = Builder::new(TABLE_CHAIR_SETTINGS);
    let floor = b.material("floor", [0.5, 0.42, 0.33]);
    let wall = b.material("wall", [0.75, 0.73, 0.7]);
    let ceiling = b.material("ceiling", [0.8, 0.8, 0.8]);
    let wood = b.material("wood", [0.55, 0.38, 0.22]);
    let blue = b.material("chair", [0.25, 0.38, 0.6]);
    room(&mut b, DVec3::new(-2.0, 0.0, -2.0), DVec3::new(2.0, 3.0, 2.0), 2, [floor, wall, ceiling]);
    let wood_cube = b.mesh("WoodCube", &unit_cube(), wood);
    let chair_cube = b.mesh("ChairCube", &unit_cube(), blue);
    let table_at = DVec3::new(0.5, 0.0, -0.5);
    add_boxes(&mut b, "Table", wood_cube, &legged_table(table_at, DVec3::new(1.2, 0.75, 0.8)));
    // The seat's front edge 10 cm under the table top's edge (z = -0.1).
    add_boxes(&mut b, "Chair", chair_cube, &legged_chair(DVec3::new(0.5, 0.0, 0.01)));

    let light_position = DVec3::new(-0.4, 2.95, 0.4);
    b.spot_light("CeilingSpot", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y), 45.0, 60.0);
    b.camera("Camera", DVec3::new(-1.7, 1.6, 1.7), DVec3::new(0.5, 0.5, -0.4), 60f64.to_radians(), None, 0.05, 20.0);
    b
}

/// A stand-in for the obscurance paper's Table 2 scene (Iones et al. 2003), a classroom of
/// about its size (1,244 triangles; this one has 1,260), not a copy of the paper's model:
/// an 8 x 3 x 7 m room (2 x 2 grids, 48 triangles), four rows of four pupils' desk and
/// chair pairs facing -Z (six boxes a pair, 1,152 triangles), a teacher's desk (four
/// boxes) and a blackboard slab on the back wall.
/// Pupils' furniture is made of panels rather than legs so that sixteen pairs fit the
/// paper's count; panels also make the enclosed gaps (under a seat, between desk sides)
/// that separate obscurance from plain distance-to-floor shading.
///
/// Lights: three spots 5 cm under the ceiling along the centre aisle (free floor below
/// them, which each lights at pi lux), pointing down with cones 45 and 60 degrees. Camera:
/// at eye height by the rear wall in the aisle, looking at the blackboard over the rows.
pub(super) fn classroom() -> Builder {
    let mut b = Builder::new(CLASSROOM_SETTINGS);
    let floor = b.material("floor", [0.45, 0.42, 0.38]);
    let wall = b.material("wall", [0.75, 0.73, 0.68]);
    let ceiling = b.material("ceiling", [0.8, 0.8, 0.8]);
    let desk = b.material("desk", [0.6, 0.45, 0.3]);
    let chair = b.material("chair", [0.3, 0.42, 0.55]);
    let teacher = b.material("teacher-desk", [0.45, 0.3, 0.18]);
    let board = b.material("blackboard", [0.06, 0.12, 0.09]);
    let (lo, hi) = (DVec3::new(-4.0, 0.0, -3.5), DVec3::new(4.0, 3.0, 3.5));
    room(&mut b, lo, hi, 2, [floor, wall, ceiling]);
    let desk_cube = b.mesh("DeskCube", &unit_cube(), desk);
    let chair_cube = b.mesh("ChairCube", &unit_cube(), chair);
    let teacher_cube = b.mesh("TeacherDeskCube", &unit_cube(), teacher);
    let board_cube = b.mesh("BlackboardCube", &unit_cube(), board);

    // Columns 1.6 m apart leave a 0.9 m aisle on the centre line and 1.25 m by the walls.
    for (row, z) in [-1.6, -0.4, 0.8, 2.0].into_iter().enumerate() {
        for (column, x) in [-2.4, -0.8, 0.8, 2.4].into_iter().enumerate() {
            let at = DVec3::new(x, 0.0, z);
            add_boxes(&mut b, &format!("Desk{row}{column}"), desk_cube, &panel_desk(at));
            // The seat's front edge 10 cm under the desk top's back edge.
            let chair_at = at + DVec3::new(0.0, 0.0, 0.36);
            add_boxes(&mut b, &format!("Chair{row}{column}"), chair_cube, &panel_chair(chair_at));
        }
    }
    add_boxes(&mut b, "TeacherDesk", teacher_cube, &teacher_desk(DVec3::new(2.2, 0.0, -2.7)));
    // 3.2 x 1.2 m, its lower edge 0.9 m up, flat on the back wall.
    add_boxes(&mut b, "", board_cube, &[("Blackboard".to_string(), DVec3::new(-1.6, 0.9, lo.z), DVec3::new(1.6, 2.1, lo.z + 0.03))]);

    for (i, z) in [-2.3, 0.0, 2.3].into_iter().enumerate() {
        let light_position = DVec3::new(0.0, hi.y - 0.05, z);
        b.spot_light(&format!("CeilingSpot{i}"), light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y), 45.0, 60.0);
    }
    b.camera("Camera", DVec3::new(0.0, 1.7, 3.3), DVec3::new(0.0, 1.0, lo.z), 55f64.to_radians(), None, 0.05, 20.0);
    b
}

/// A box by its name and its lower and upper corners, metres.
pub(super) type Part = (String, DVec3, DVec3);

/// Adds each part as a node `prefix` + name scaling the shared unit cube `cube`, so the
/// furniture costs one mesh per material however many boxes it has; every box is closed
/// with faces outward (the cube's), and a node transform keeps that.
pub(super) fn add_boxes(b: &mut Builder, prefix: &str, cube: usize, parts: &[Part]) {
    for (name, lo, hi) in parts {
        b.mesh_node(&format!("{prefix}{name}"), cube, (*lo + *hi) * 0.5, *hi - *lo);
    }
}

/// Four boxes under the corners of the footprint `lo`..`hi` (x and z), `side` metres square
/// and `inset` in from the edges, from y = `lo.y` up to `hi.y`.
pub(super) fn legs(lo: DVec3, hi: DVec3, side: f64, inset: f64) -> Vec<Part> {
    let mut legs = Vec::with_capacity(4);
    for (i, (x, z)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
        let x0 = if x == 0 { lo.x + inset } else { hi.x - inset - side };
        let z0 = if z == 0 { lo.z + inset } else { hi.z - inset - side };
        legs.push((format!("Leg{i}"), DVec3::new(x0, lo.y, z0), DVec3::new(x0 + side, hi.y, z0 + side)));
    }
    legs
}

/// A table standing at `at` (the middle of its footprint on the floor): a `size.x` by
/// `size.z` top 4 cm thick with its upper face at `size.y`, on four 6 cm square legs set
/// 4 cm in from the corners. Legs end under the top rather than going through it, so no
/// surface is hidden inside another box.
pub(super) fn legged_table(at: DVec3, size: DVec3) -> Vec<Part> {
    let half = DVec3::new(size.x * 0.5, 0.0, size.z * 0.5);
    let under_top = at.y + size.y - 0.04;
    let mut parts = vec![(
        "Top".to_string(),
        DVec3::new(at.x - half.x, under_top, at.z - half.z),
        DVec3::new(at.x + half.x, at.y + size.y, at.z + half.z),
    )];
    parts.extend(legs(at - half, DVec3::new(at.x + half.x, under_top, at.z + half.z), 0.06, 0.04));
    parts
}

/// A chair standing at `at` (the middle of its footprint), facing -Z: a 42 cm square seat
/// 4 cm thick with its top at 45 cm, four 4 cm square legs set 2 cm in from its corners,
/// and a 4 cm backrest standing on the seat's +Z edge up to 90 cm.
pub(super) fn legged_chair(at: DVec3) -> Vec<Part> {
    let half = DVec3::new(0.21, 0.0, 0.21);
    let (under_seat, seat_top) = (at.y + 0.41, at.y + 0.45);
    let mut parts = vec![
        ("Seat".to_string(), DVec3::new(at.x - half.x, under_seat, at.z - half.z), DVec3::new(at.x + half.x, seat_top, at.z + half.z)),
        (
            "Back".to_string(),
            DVec3::new(at.x - half.x, seat_top, at.z + half.z - 0.04),
            DVec3::new(at.x + half.x, at.y + 0.9, at.z + half.z),
        ),
    ];
    parts.extend(legs(at - half, DVec3::new(at.x + half.x, under_seat, at.z + half.z), 0.04, 0.02));
    parts
}

/// A pupil's desk at `at` (the middle of its footprint): a 70 x 50 cm top 3 cm thick with
/// its upper face at 72 cm, on two 3 cm side panels set 3 cm in from its ends and 2 cm in
/// from its front and back.
pub(super) fn panel_desk(at: DVec3) -> Vec<Part> {
    let (hx, hz) = (0.35, 0.25);
    let under_top = at.y + 0.69;
    let mut parts = vec![("Top".to_string(), DVec3::new(at.x - hx, under_top, at.z - hz), DVec3::new(at.x + hx, at.y + 0.72, at.z + hz))];
    for (i, x0) in [at.x - hx + 0.03, at.x + hx - 0.06].into_iter().enumerate() {
        parts.push((format!("Side{i}"), DVec3::new(x0, at.y, at.z - hz + 0.02), DVec3::new(x0 + 0.03, under_top, at.z + hz - 0.02)));
    }
    parts
}

/// A pupil's chair at `at` (the middle of its 40 x 42 cm footprint), facing -Z: a 40 cm
/// square seat 3 cm thick with its top at 45 cm, resting on a 2 cm front panel under its
/// front edge and against a 2 cm back panel behind it that rises to 85 cm as the backrest.
pub(super) fn panel_chair(at: DVec3) -> Vec<Part> {
    let (hx, hz) = (0.2, 0.21);
    let (front, back) = (at.z - hz, at.z + hz - 0.02);
    let under_seat = at.y + 0.42;
    vec![
        ("Seat".to_string(), DVec3::new(at.x - hx, under_seat, front), DVec3::new(at.x + hx, at.y + 0.45, back)),
        ("Front".to_string(), DVec3::new(at.x - hx, at.y, front), DVec3::new(at.x + hx, under_seat, front + 0.02)),
        ("Back".to_string(), DVec3::new(at.x - hx, at.y, back), DVec3::new(at.x + hx, at.y + 0.85, back + 0.02)),
    ]
}

/// The teacher's desk at `at` (the middle of its footprint): a 140 x 70 cm top 4 cm thick
/// with its upper face at 76 cm, on two 4 cm side panels under its ends, with a 2 cm
/// modesty panel on the pupils' side (+Z) between them from 25 cm up to the top.
pub(super) fn teacher_desk(at: DVec3) -> Vec<Part> {
    let (hx, hz) = (0.7, 0.35);
    let under_top = at.y + 0.72;
    let mut parts = vec![("Top".to_string(), DVec3::new(at.x - hx, under_top, at.z - hz), DVec3::new(at.x + hx, at.y + 0.76, at.z + hz))];
    for (i, x0) in [at.x - hx, at.x + hx - 0.04].into_iter().enumerate() {
        parts.push((format!("Side{i}"), DVec3::new(x0, at.y, at.z - hz), DVec3::new(x0 + 0.04, under_top, at.z + hz)));
    }
    parts.push((
        "Front".to_string(),
        DVec3::new(at.x - hx + 0.04, at.y + 0.25, at.z + hz - 0.02),
        DVec3::new(at.x + hx - 0.04, under_top, at.z + hz),
    ));
    parts
}

/// A stand-in for 003's Fig. 12 scene (the bunny over a plane under the Eucalyptus Grove
/// probe): two instances of one lumpy blob (radius 0.4 m, 1,280 triangles; one type, one
/// table) and a box over the occluder scenes' 4 x 4 m ground, lit only by `envs/sky.exr`
/// (a sky with a small sun, [`super::environments`]). The blobs and the box are FIV's
/// occluders; the ground is the receiver whose shadows the paper measures.
pub(super) fn fiv_blobs() -> Builder {
    let (mut b, grey) = grey_over_ground();
    let blob_mesh = b.mesh("Blob", &blob(0.4, 3), grey);
    b.occluder_node("Blob", blob_mesh, DVec3::new(-0.5, 0.7, 0.2), DVec3::ONE);
    b.occluder_node("Blob.001", blob_mesh, DVec3::new(0.6, 0.55, -0.5), DVec3::ONE);
    let cube = b.mesh("Cube", &unit_cube(), grey);
    b.occluder_node("Box", cube, DVec3::new(0.5, 0.2, 0.8), DVec3::splat(0.4));
    under_the_sky(b, 0.2)
}

/// The occluder scenes' 4 x 4 m ground and the grey of their occluders.
fn grey_over_ground() -> (Builder, usize) {
    let mut b = Builder::new(OCCLUDER_SETTINGS);
    ground(&mut b);
    let grey = b.material("occluder", [0.5, 0.5, 0.5]);
    (b, grey)
}

/// Lit by `envs/sky.exr`, seen from 2.8 m up and 3.6 m back, looking at `target_y` over the
/// origin.
fn under_the_sky(mut b: Builder, target_y: f64) -> Builder {
    b.environment("envs/sky.exr", 1.0);
    b.camera("Camera", DVec3::new(0.0, 2.8, 3.6), DVec3::new(0.0, target_y, 0.0), 45f64.to_radians(), None, 0.1, 20.0);
    b
}

/// The paper's other stand-ins (003 Table 1, Fig. 12 and 18): a bunny-sized lumpy blob
/// (81,920 triangles, 40,962 vertices against the bunny's 35,947) and two instances of a
/// tree-like occluder (a trunk under a crown of three blobs, apart: one closed mesh of four
/// parts, 2,088 vertices; gaps and concavities, so it shades itself) over the ground under
/// the sky. Smooth meshes: the blob's file is a quarter of a flat-shaded one.
pub(super) fn fiv_garden() -> Builder {
    let (mut b, grey) = grey_over_ground();
    let bunny = b.smooth_mesh("Bunny", &blob(0.4, 6), grey);
    b.occluder_node("Bunny", bunny, DVec3::new(-0.7, 0.5, 0.2), DVec3::ONE);
    let tree = b.smooth_mesh("Tree", &tree(), grey);
    b.occluder_node("Tree", tree, DVec3::new(0.6, 0.0, -0.6), DVec3::ONE);
    b.occluder_node("Tree.001", tree, DVec3::new(0.8, 0.0, 0.8), DVec3::ONE);
    under_the_sky(b, 0.4)
}

/// A tree-like closed occluder standing at the origin: a trunk (an ellipsoid 0.1 m wide and
/// 0.5 m high, 320 triangles) and a crown of three lumpy blobs (radius 0.18 m, 1,280
/// triangles each) that touch neither the trunk nor each other; every part smooth.
fn tree() -> Vec<[DVec3; 3]> {
    let stretch = |p: DVec3| p * DVec3::new(0.05, 0.25, 0.05) + DVec3::new(0.0, 0.25, 0.0);
    let trunk = relume_bake::testing::icosphere(2).into_iter().map(move |t| t.map(stretch));
    let crown = [DVec3::new(0.0, 1.05, 0.0), DVec3::new(-0.28, 0.72, 0.15), DVec3::new(0.27, 0.74, -0.16)];
    let blobs = crown.into_iter().flat_map(|at| blob(0.18, 3).into_iter().map(move |t| t.map(|p| p + at)));
    trunk.chain(blobs).collect()
}

/// 003 Table 2's occluder counts: `count` instances of the `fiv-blobs` blob (one type, one
/// table) on a square grid 1.2 m apart, 0.6 m over a ground that holds them with a metre to
/// spare, under the sky, seen from above: the occluder-sum pass's cost against the number of
/// occluders.
pub(super) fn fiv_crowd(count: usize) -> Builder {
    let mut b = Builder::new(OCCLUDER_SETTINGS);
    let side = (count as f64).sqrt().ceil() as usize;
    let spacing = 1.2;
    let half = 0.5 * spacing * side as f64 + 1.0;
    ground_of_half_size(&mut b, half);
    let grey = b.material("occluder", [0.5, 0.5, 0.5]);
    let blob_mesh = b.mesh("Blob", &blob(0.4, 3), grey);
    for k in 0..count {
        let (i, j) = ((k % side) as f64, (k / side) as f64);
        let at = DVec3::new((i - 0.5 * (side - 1) as f64) * spacing, 0.6, (j - 0.5 * (side - 1) as f64) * spacing);
        b.occluder_node(&format!("Blob.{k:03}"), blob_mesh, at, DVec3::ONE);
    }
    b.environment("envs/sky.exr", 1.0);
    b.camera("Camera", DVec3::new(0.0, 2.0 * half, 1.2 * half), DVec3::ZERO, 45f64.to_radians(), None, 0.1, 100.0);
    b
}
