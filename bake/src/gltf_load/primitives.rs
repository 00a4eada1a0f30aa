//! Primitives into meshes: accessors read with checked arithmetic, triangle lists, strips and
//! fans as triangle lists, world-space positions and normals, degenerate triangles dropped.

use super::{quoted_name, Ctx, ErrorKind, Loader, SceneError};
use crate::scene::Mesh;
use glam::{Mat3, Mat4, Vec2, Vec3};

impl Loader<'_> {
    pub(super) fn load_primitive(
        &mut self,
        node_name: Option<&str>,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        world: Mat4,
    ) -> Result<Option<Mesh>, SceneError> {
        let ctx = self.ctx;
        let mesh_item = quoted_name("mesh", mesh.name(), mesh.index());
        let item = format!("{mesh_item} primitive {}", primitive.index());
        // Named after the node (instances of one glTF mesh are told apart), else the mesh.
        let base = node_name
            .filter(|n| !n.is_empty())
            .or(mesh.name().filter(|n| !n.is_empty()))
            .map(str::to_string)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let name = match mesh.primitives().len() {
            1 => base,
            _ => format!("{base} primitive {}", primitive.index()),
        };
        triangle_mode(primitive.mode()).map_err(|(problem, fix)| ctx.fail(ErrorKind::NotTriangles, item.clone(), problem, fix))?;
        let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
            return Err(ctx.fail(ErrorKind::Accessor, item, "has no POSITION attribute", "add a POSITION accessor"));
        };
        let positions: Vec<Vec3> =
            self.read_vectors::<3>(&item, "POSITION", &position_accessor, false)?.into_iter().map(Vec3::from).collect();
        let vertex_count = positions.len();
        check_finite(ctx, &item, "POSITION", positions.iter().map(|p| p.to_array()))?;

        let normals_in: Option<Vec<Vec3>> = match primitive.get(&gltf::Semantic::Normals) {
            Some(a) => {
                let n: Vec<Vec3> = self.read_vectors::<3>(&item, "NORMAL", &a, false)?.into_iter().map(Vec3::from).collect();
                self.check_count(&item, "NORMAL", n.len(), vertex_count)?;
                check_finite(ctx, &item, "NORMAL", n.iter().map(|v| v.to_array()))?;
                Some(n)
            }
            None => None,
        };
        let mut uvs: [Option<Vec<Vec2>>; 2] = [None, None];
        for (set, slot) in uvs.iter_mut().enumerate() {
            if let Some(a) = primitive.get(&gltf::Semantic::TexCoords(set as u32)) {
                let what = format!("TEXCOORD_{set}");
                let uv: Vec<Vec2> = self.read_vectors::<2>(&item, &what, &a, true)?.into_iter().map(Vec2::from).collect();
                self.check_count(&item, &what, uv.len(), vertex_count)?;
                check_finite(ctx, &item, &what, uv.iter().map(|v| v.to_array()))?;
                *slot = Some(uv);
            }
        }
        let [uv0, uv1] = uvs;

        let sequence: Vec<u32> = match primitive.indices() {
            Some(a) => self.read_indices(&item, &a)?,
            None => {
                let n = u32::try_from(vertex_count).map_err(|_| {
                    ctx.fail(
                        ErrorKind::Accessor,
                        item.clone(),
                        format!("{vertex_count} vertices without indices"),
                        "split the mesh below 2^32 vertices",
                    )
                })?;
                (0..n).collect()
            }
        };
        if let Some((at, &bad)) = sequence.iter().enumerate().find(|(_, &i)| i as usize >= vertex_count) {
            return Err(ctx.fail(
                ErrorKind::IndexOutOfRange,
                item,
                format!("index {bad} (at position {at}) out of range ({vertex_count} vertices)"),
                "fix the indices accessor",
            ));
        }
        let counted = match primitive.indices() {
            Some(_) => Counted { what: "index", accessor: "indices" },
            None => Counted { what: "vertex (no indices)", accessor: "POSITION" },
        };
        let mut indices = triangle_list(primitive.mode(), sequence, counted)
            .map_err(|(problem, fix)| ctx.fail(ErrorKind::NotTriangles, item.clone(), problem, fix))?;

        // World space. Normals go through the inverse-transpose, computed as the cofactor
        // matrix (columns b×c, c×a, a×b) so that singular scales do not divide by zero; the
        // sign of the determinant keeps its orientation, and a mirroring transform (negative
        // determinant) flips the winding so the front face stays the one the normals face.
        let world_positions: Vec<Vec3> = positions.iter().map(|&p| world.transform_point3(p)).collect();
        if let Some(v) = world_positions.iter().position(|p| !p.is_finite()) {
            return Err(ctx.fail(
                ErrorKind::NonFinite,
                item,
                format!("vertex {v} is not finite after the node transform"),
                "fix the node transform's scale or the POSITION data's magnitude",
            ));
        }
        if let Some(v) = world_positions.iter().position(|p| p.abs().max_element() > crate::scene::MAX_COORDINATE) {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                format!("vertex {v} lies at {} after the node transform, past 1e7 m from the origin", world_positions[v]),
                "fix the node transform's scale or the POSITION data's magnitude (or move the model nearer the origin)",
            ));
        }
        let linear = Mat3::from_mat4(world);
        let det = linear.determinant();
        let cofactor =
            Mat3::from_cols(linear.y_axis.cross(linear.z_axis), linear.z_axis.cross(linear.x_axis), linear.x_axis.cross(linear.y_axis));
        let normal_matrix = if det < 0.0 { -cofactor } else { cofactor };
        if det < 0.0 {
            for tri in indices.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }

        // Drop zero-area triangles: they carry no light, and they make a BVH, a lightmap
        // rasteriser and per-face normals divide by zero. Relative to the longest edge, so
        // that the test does not depend on the scene's scale.
        let before = indices.len() / 3;
        let mut kept = Vec::with_capacity(indices.len());
        for tri in indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| world_positions[i as usize]);
            let area2 = (b - a).cross(c - a).length();
            let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
            if area2 > 1e-7 * longest && area2 > 0.0 {
                kept.extend_from_slice(tri);
            }
        }
        let dropped = before - kept.len() / 3;
        if dropped > 0 {
            self.warnings.push(ctx.warning(&item, &format!("dropped {dropped} degenerate (zero-area) triangles of {before}")));
        }
        if kept.is_empty() {
            self.warnings.push(ctx.warning(&item, "has no triangles left; primitive skipped"));
            return Ok(None);
        }
        let indices = kept;

        // Area-weighted vertex normals (the unnormalised cross product is twice the area),
        // used where the file has none, or where its normal vanishes under the transform.
        let mut geometric = vec![Vec3::ZERO; vertex_count];
        let mut normals: Vec<Vec3> = match &normals_in {
            Some(n) => n.iter().map(|&v| (normal_matrix * v).normalize_or_zero()).collect(),
            None => vec![Vec3::ZERO; vertex_count],
        };
        if normals.contains(&Vec3::ZERO) {
            for tri in indices.chunks_exact(3) {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| world_positions[i as usize]);
                let face = (b - a).cross(c - a);
                for &i in tri {
                    geometric[i as usize] += face;
                }
            }
            for (n, g) in normals.iter_mut().zip(&geometric) {
                if *n == Vec3::ZERO {
                    // A vertex no kept triangle uses gets any unit normal: nothing reads it.
                    *n = g.normalize_or(Vec3::Y);
                }
            }
        }

        let material = self.material_for(primitive, &item)?;
        if self.scene.materials[material].base_color_texture.is_some() && uv0.is_none() {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                item,
                format!(
                    "its material \"{}\" has a baseColorTexture but the primitive has no TEXCOORD_0",
                    self.scene.materials[material].name
                ),
                "add TEXCOORD_0 to the primitive or remove the texture from the material",
            ));
        }

        Ok(Some(Mesh { name, positions: world_positions, normals, uv0, uv1, indices, material }))
    }

    pub(super) fn check_count(&self, item: &str, what: &str, count: usize, vertex_count: usize) -> Result<(), SceneError> {
        if count != vertex_count {
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                item,
                format!("{what} has {count} elements but POSITION has {vertex_count}"),
                format!("give {what} one element per vertex"),
            ));
        }
        Ok(())
    }

    /// The bytes an accessor reads, checked: (buffer data, first byte, stride, element size).
    pub(super) fn accessor_span(
        &self,
        item: &str,
        what: &str,
        accessor: &gltf::Accessor,
        element_size: usize,
    ) -> Result<(&[u8], usize, usize), SceneError> {
        let ctx = self.ctx;
        let acc_item = format!("{item}: {what} accessor {}", accessor.index());
        if accessor.sparse().is_some() {
            return Err(ctx.fail(ErrorKind::Unsupported, acc_item, "is sparse", "export without sparse accessors"));
        }
        let Some(view) = accessor.view() else {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                "has no bufferView",
                "point the accessor at a bufferView holding its data",
            ));
        };
        let buffer = view.buffer();
        let data: &[u8] = self.buffers.get(buffer.index()).map(|b| b.as_ref()).unwrap_or(&[]);
        let view_end = view.offset().checked_add(view.length());
        match view_end {
            Some(end) if end <= data.len() => {}
            _ => {
                return Err(ctx.fail(
                    ErrorKind::Buffer,
                    format!("bufferView {}", view.index()),
                    format!(
                        "bytes {}..{} reach past the end of buffer {} ({} bytes)",
                        view.offset(),
                        view.offset() as u128 + view.length() as u128,
                        buffer.index(),
                        data.len()
                    ),
                    "fix the bufferView's byteOffset and byteLength, or the buffer",
                ))
            }
        }
        let stride = view.stride().unwrap_or(element_size);
        if stride < element_size {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                format!("bufferView {} has byteStride {stride}, less than the {element_size}-byte element", view.index()),
                "fix the bufferView's byteStride",
            ));
        }
        let count = accessor.count();
        let start = view.offset().checked_add(accessor.offset());
        let end = match count {
            0 => start,
            n => start.and_then(|s| stride.checked_mul(n - 1).and_then(|x| x.checked_add(s))).and_then(|x| x.checked_add(element_size)),
        };
        let view_end = view.offset() + view.length();
        match (start, end) {
            (Some(s), Some(e)) if e <= view_end => Ok((data, s, stride)),
            _ => Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                format!(
                    "{count} elements of {element_size} bytes (stride {stride}) from byteOffset {} read past the end of bufferView {} ({} bytes)",
                    accessor.offset(),
                    view.index(),
                    view.length()
                ),
                "fix the accessor's count or byteOffset, or the bufferView's byteLength",
            )),
        }
    }

    /// Reads a float vector attribute. `normalized_ok` admits normalized unsigned bytes and
    /// shorts, which glTF allows for texture coordinates.
    pub(super) fn read_vectors<const N: usize>(
        &self,
        item: &str,
        what: &str,
        accessor: &gltf::Accessor,
        normalized_ok: bool,
    ) -> Result<Vec<[f32; N]>, SceneError> {
        use gltf::accessor::{DataType, Dimensions};
        let dims = match accessor.dimensions() {
            Dimensions::Vec2 => 2,
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            _ => 0,
        };
        let ty = accessor.data_type();
        let ok_type = ty == DataType::F32 || (normalized_ok && accessor.normalized() && matches!(ty, DataType::U8 | DataType::U16));
        if dims != N || !ok_type {
            let allowed = if normalized_ok { "float, or normalized unsigned byte/short" } else { "float" };
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                format!("{item}: {what} accessor {}", accessor.index()),
                format!("is {:?} {:?}{}", accessor.dimensions(), ty, if accessor.normalized() { " normalized" } else { "" }),
                format!("{what} must be VEC{N} of {allowed}"),
            ));
        }
        let size = ty.size();
        let (data, start, stride) = self.accessor_span(item, what, accessor, size * N)?;
        let mut out = Vec::with_capacity(accessor.count());
        for e in 0..accessor.count() {
            let base = start + e * stride;
            let mut v = [0.0f32; N];
            for (c, slot) in v.iter_mut().enumerate() {
                let at = base + c * size;
                // In range: accessor_span checked the last element's end.
                let b = &data[at..at + size];
                *slot = match ty {
                    DataType::U8 => b[0] as f32 / 255.0,
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
                    _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                };
            }
            out.push(v);
        }
        Ok(out)
    }

    pub(super) fn read_indices(&self, item: &str, accessor: &gltf::Accessor) -> Result<Vec<u32>, SceneError> {
        use gltf::accessor::{DataType, Dimensions};
        let ty = accessor.data_type();
        if accessor.dimensions() != Dimensions::Scalar || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                format!("{item}: indices accessor {}", accessor.index()),
                format!("is {:?} {:?}", accessor.dimensions(), ty),
                "indices must be SCALAR unsigned byte, short or int",
            ));
        }
        let size = ty.size();
        let (data, start, stride) = self.accessor_span(item, "indices", accessor, size)?;
        let mut out = Vec::with_capacity(accessor.count());
        for e in 0..accessor.count() {
            let at = start + e * stride;
            let b = &data[at..at + size];
            out.push(match ty {
                DataType::U8 => b[0] as u32,
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            });
        }
        Ok(out)
    }
}

pub(super) fn check_finite<const N: usize>(
    ctx: Ctx,
    item: &str,
    what: &str,
    values: impl Iterator<Item = [f32; N]>,
) -> Result<(), SceneError> {
    for (v, value) in values.enumerate() {
        if value.iter().any(|c| !c.is_finite()) {
            return Err(ctx.fail(
                ErrorKind::NonFinite,
                item,
                format!("vertex {v} has a non-finite {what} {value:?}"),
                format!("fix the {what} data (NaN or infinity in the buffer)"),
            ));
        }
    }
    Ok(())
}

/// What a primitive's vertex sequence counts, for the refusals: its indices, or its vertices
/// when it has none.
#[derive(Clone, Copy)]
pub(super) struct Counted {
    pub what: &'static str,
    pub accessor: &'static str,
}

/// Refuses points and lines; the error is (problem, fix).
pub(super) fn triangle_mode(mode: gltf::mesh::Mode) -> Result<(), (String, String)> {
    use gltf::mesh::Mode;
    match mode {
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => Ok(()),
        other => {
            Err((format!("mode {other:?} is not triangles"), "export the mesh as triangles (a list, strip or fan: mode 4, 5 or 6)".into()))
        }
    }
}

/// The triangles of a primitive of `mode` whose vertices come in `sequence` (its indices, or
/// 0..n), as a triangle list (glTF 2.0 §3.7.2.1): a strip's triangle i is (i, i+1, i+2) for
/// even i and (i, i+2, i+1) for odd i, so every triangle keeps the strip's winding, and the
/// triangles that repeat a vertex (a strip's stitches) are left out; a fan's is (i+1, i+2, 0).
/// Points and lines are refused, as is a list whose count is not a multiple of 3 or a strip or
/// fan of fewer than 3. The error is (problem, fix).
pub(super) fn triangle_list(mode: gltf::mesh::Mode, sequence: Vec<u32>, counted: Counted) -> Result<Vec<u32>, (String, String)> {
    use gltf::mesh::Mode;
    triangle_mode(mode)?;
    let (n, Counted { what, accessor }) = (sequence.len(), counted);
    match mode {
        Mode::Triangles if n.is_multiple_of(3) => Ok(sequence),
        Mode::Triangles => Err((
            format!("{what} count {n} is not a multiple of 3"),
            format!("a triangle list needs three indices per triangle; fix the {accessor} accessor count"),
        )),
        Mode::TriangleStrip | Mode::TriangleFan if n < 3 => Err((
            format!("a triangle {} of {what} count {n}", if mode == Mode::TriangleStrip { "strip" } else { "fan" }),
            format!("a strip or fan needs at least 3 vertices; fix the {accessor} accessor count"),
        )),
        Mode::TriangleStrip => Ok((0..n - 2)
            .map(|i| if i % 2 == 0 { [i, i + 1, i + 2] } else { [i, i + 2, i + 1] }.map(|k| sequence[k]))
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .flatten()
            .collect()),
        _ => Ok((0..n - 2).flat_map(|i| [i + 1, i + 2, 0]).map(|i| sequence[i]).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::{Counted, Counted as C};
    use gltf::mesh::Mode;

    const INDICES: Counted = C { what: "index", accessor: "indices" };

    fn triangle_list(mode: Mode, sequence: Vec<u32>) -> Result<Vec<u32>, (String, String)> {
        super::triangle_list(mode, sequence, INDICES)
    }

    #[test]
    fn strips_and_fans_become_lists_with_the_winding_kept() {
        assert_eq!(triangle_list(Mode::Triangles, vec![3, 4, 5]), Ok(vec![3, 4, 5]));
        // Strip 0 1 2 3 4: triangles 012, 132 (turned to keep the winding), 234.
        assert_eq!(triangle_list(Mode::TriangleStrip, vec![0, 1, 2, 3, 4]), Ok(vec![0, 1, 2, 1, 3, 2, 2, 3, 4]));
        assert_eq!(triangle_list(Mode::TriangleStrip, vec![7, 8, 9, 6]), Ok(vec![7, 8, 9, 8, 6, 9]));
        // Fan around 10: 10 11 12, 10 12 13 (as (i+1, i+2, 0): 11 12 10, 12 13 10).
        assert_eq!(triangle_list(Mode::TriangleFan, vec![10, 11, 12, 13]), Ok(vec![11, 12, 10, 12, 13, 10]));
        assert!(triangle_list(Mode::TriangleStrip, vec![0, 1]).unwrap_err().0.contains("strip"));
        assert!(triangle_list(Mode::Triangles, vec![0, 1, 2, 3]).unwrap_err().0.contains("not a multiple of 3"));
        assert!(triangle_list(Mode::Lines, vec![0, 1]).unwrap_err().0.contains("Lines"));
        // A stitched strip (0 1 2 2 3 3 4 5: two strips joined by repeated indices) keeps only
        // the real triangles: 012, then 354 (position 5 is odd, so turned).
        assert_eq!(triangle_list(Mode::TriangleStrip, vec![0, 1, 2, 2, 3, 3, 4, 5]), Ok(vec![0, 1, 2, 3, 5, 4]));
    }
}
