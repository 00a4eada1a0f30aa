//! FIV's surfaces pass (graphics): every pixel's world position (alpha 1 where a surface is)
//! and interpolated normal, rasterised as the lighting pass rasterises (the same position
//! expression from the same buffers), so the occluder sums cover the pixels the lighting
//! pass shades (the GPU test checks the lighting pass's pixels against this pass's).
//!
//! Reads: the scene's vertex and index buffers and the frame's uniforms. Writes: `positions`
//! (xyz, w 1 on a surface) and `normals` (unit, towards the viewer; w the occluder the
//! surface belongs to plus one, 0 for none), colour attachments cleared to 0, and its own
//! depth. Cost: one draw per mesh (the push constant names its occluder).

use crate::passes::compute::Slot;
use crate::passes::graphics::{GraphicsPass, Shaders, Target};
use crate::passes::lighting::DEPTH_FORMAT;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{vk, CommandRecorder, Image, ImageDesc, Tracker, VkResult};

pub(super) const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub(super) struct SurfacesPass {
    pass: GraphicsPass<u32, 2>,
    pub positions: Image,
    pub normals: Image,
    depth: Image,
    /// Per mesh its occluder index + 1 (0: none), its first index and its count of indices.
    draws: Vec<(u32, u32, u32)>,
}

impl SurfacesPass {
    /// `occluder_of_mesh[m]`: the occluder index + 1 of the scene's mesh m, 0 for none.
    pub fn new(shared: &Shared, occluder_of_mesh: &[u32]) -> VkResult<SurfacesPass> {
        let (ctx, settings) = (shared.ctx, shared.settings);
        let target = |name, format, usage| {
            let desc = ImageDesc {
                width: settings.width,
                height: settings.height,
                layers: 1,
                format,
                usage,
                view_type: vk::ImageViewType::TYPE_2D,
            };
            Image::new(ctx, name, desc)
        };
        use vk::ImageUsageFlags as U;
        let surface_usage = U::COLOR_ATTACHMENT | U::STORAGE | U::TRANSFER_SRC;
        let positions = target("fiv positions", SURFACE_FORMAT, surface_usage)?;
        let normals = target("fiv normals", SURFACE_FORMAT, surface_usage)?;
        let depth = target("fiv depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?;
        let shaders =
            Shaders { vertex: shaders::FIV_SURFACES_VERT, fragment: shaders::FIV_SURFACES_FRAG, specialization: &[], attributes: 2 };
        let slots = [Slot::Uniform(&shared.gpu_scene.frame)];
        let pass = GraphicsPass::new(ctx, "fiv.surfaces", shared.gpu_scene, &shaders, &slots, ([&positions, &normals], &depth))?;
        let draws = shared.gpu_scene.draws.iter().zip(occluder_of_mesh).map(|(d, id)| (*id, d.first_index, d.index_count)).collect();
        Ok(SurfacesPass { pass, positions, normals, depth, draws })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        let target = Target {
            extent: self.positions.desc.extent(),
            colors: [self.positions.view, self.normals.view],
            clear: [0.0; 4],
            depth: self.depth.view,
        };
        self.pass.record(rec, tracker, target, self.draws.iter().copied());
    }
}
