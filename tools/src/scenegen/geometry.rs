//! Flat-shaded geometry: quads facing a given way, rooms, unit cubes.

use super::gltf_writer::Builder;
use glam::DVec3;

/// Two triangles of the quad a, b, c, d, each wound counter-clockwise (glTF's front face)
/// as seen from the side `outward(centroid)` points to.
pub(super) fn quad_facing(q: [DVec3; 4], outward: impl Fn(DVec3) -> DVec3) -> Vec<[DVec3; 3]> {
    [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        .into_iter()
        .map(|[a, b, c]| {
            let centroid = (a + b + c) / 3.0;
            if (b - a).cross(c - a).dot(outward(centroid)) >= 0.0 {
                [a, b, c]
            } else {
                [a, c, b]
            }
        })
        .collect()
}

/// The inside of the room from `lo` to `hi`: floor, ceiling and four walls, each a
/// `split` x `split` grid of quads facing into the room, with materials `[floor, walls,
/// ceiling]`. Walls are named as seen by a camera looking down -Z, like `cornell`'s:
/// BackWall at `lo.z`, FrontWall at `hi.z`, LeftWall at `lo.x`, RightWall at `hi.x`. The
/// grid changes no surface; it brings a scene's triangle count near the paper scene's.
pub(super) fn room(b: &mut Builder, lo: DVec3, hi: DVec3, split: usize, materials: [usize; 3]) {
    let [floor, walls, ceiling] = materials;
    let centre = (lo + hi) * 0.5;
    let surfaces = [
        ("Floor", 1, lo.y, floor),
        ("Ceiling", 1, hi.y, ceiling),
        ("BackWall", 2, lo.z, walls),
        ("FrontWall", 2, hi.z, walls),
        ("LeftWall", 0, lo.x, walls),
        ("RightWall", 0, hi.x, walls),
    ];
    for (name, axis, at, material) in surfaces {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        // (1 - t) lo + t hi, exact at both ends so that neighbouring surfaces share edges.
        let corner = |i: usize, j: usize| {
            let (s, t) = (i as f64 / split as f64, j as f64 / split as f64);
            let mut p = DVec3::ZERO;
            p[axis] = at;
            p[u] = (1.0 - s) * lo[u] + s * hi[u];
            p[v] = (1.0 - t) * lo[v] + t * hi[v];
            p
        };
        let mut tris = Vec::with_capacity(2 * split * split);
        for i in 0..split {
            for j in 0..split {
                let quad = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)];
                tris.extend(quad_facing(quad, |c| centre - c));
            }
        }
        let mesh = b.mesh(name, &tris, material);
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }
}

/// A closed cube of side 1 centred on the origin, faces outward (12 triangles). Closed,
/// because shadow maps and ray tracers must see the occluder from the light's side too.
pub(super) fn unit_cube() -> Vec<[DVec3; 3]> {
    let mut tris = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut n = DVec3::ZERO;
            n[axis] = sign;
            let (u, v) = (DVec3::AXES[(axis + 1) % 3], DVec3::AXES[(axis + 2) % 3]);
            let c = n * 0.5;
            let quad = [c - 0.5 * u - 0.5 * v, c + 0.5 * u - 0.5 * v, c + 0.5 * u + 0.5 * v, c - 0.5 * u + 0.5 * v];
            tris.extend(quad_facing(quad, |_| n));
        }
    }
    tris
}

/// A closed, lumpy sphere (a stand-in for 003's bunny: convex in places, concave in others):
/// the unit icosphere subdivided `subdivisions` times (20 * 4^n triangles), each vertex pushed
/// out to radius(direction) = `radius` (1 + 0.15 sin 3x sin 4y cos 2z). Vertices shared by
/// triangles are computed from the same numbers, so the mesh stays closed.
pub(super) fn blob(radius: f64, subdivisions: u32) -> Vec<[DVec3; 3]> {
    let lump = |d: DVec3| d * radius * (1.0 + 0.15 * (3.0 * d.x).sin() * (4.0 * d.y).sin() * (2.0 * d.z).cos());
    relume_bake::testing::icosphere(subdivisions).iter().map(|t| t.map(lump)).collect()
}

/// One step of a 64-bit LCG (Knuth's MMIX constants): the same levels and jitter on every
/// machine.
pub(super) fn lcg(state: &mut u64) -> u64 {
    *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *state
}
