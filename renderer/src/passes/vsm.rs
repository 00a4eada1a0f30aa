//! Variance shadow maps, moments pass (000 §3.4): every shadow layer of every light renders
//! the scene's depth from the light and stores its first two moments in a layer of one
//! RG32F array image.

use super::compute::Slot;
use super::graphics::{GraphicsPass, Shaders, Target};
use crate::gpu_scene::GpuScene;
use crate::shaders;
use crate::vk::{vk, CommandRecorder, Context, Image, ImageDesc, ImageView, Tracker, VkResult};
use std::sync::Arc;

pub const MOMENTS_FORMAT: vk::Format = vk::Format::R32G32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VsmPush {
    light: u32,
    layer: u32,
}

pub struct VsmPass {
    pass: GraphicsPass<VsmPush, 1>,
    layer_views: Vec<ImageView>,
    /// The moments of every layer; the blur pass, the lighting pass and techniques' passes (light path maps' entry irradiance) read it.
    pub moments: Image,
    depth: Image,
}

impl VsmPass {
    pub(crate) fn new(ctx: &Arc<Context>, scene: &GpuScene, size: u32) -> VkResult<VsmPass> {
        let layers = scene.shadow_views.len().max(1) as u32;
        let moments = Image::new(
            ctx,
            "vsm moments",
            ImageDesc {
                width: size,
                height: size,
                layers,
                format: MOMENTS_FORMAT,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let depth = Image::new(
            ctx,
            "vsm depth",
            ImageDesc {
                width: size,
                height: size,
                layers: 1,
                format: vk::Format::D32_SFLOAT,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                view_type: vk::ImageViewType::TYPE_2D,
            },
        )?;
        let layer_views = (0..layers).map(|l| moments.layer_view(l)).collect::<VkResult<Vec<_>>>()?;
        let shaders =
            Shaders { vertex: shaders::VSM_MOMENTS_VERT, fragment: shaders::VSM_MOMENTS_FRAG, specialization: &[], attributes: 1 };
        let slots = [Slot::Updated(&scene.lights), Slot::Updated(&scene.layers)];
        let pass = GraphicsPass::new(ctx, "vsm_moments", scene, &shaders, &slots, ([&moments], &depth))?;
        Ok(VsmPass { pass, moments, depth, layer_views })
    }

    /// Writes: `moments` (colour attachment), its depth buffer. Reads: scene buffers.
    /// Texels no geometry covers keep the layer's far depth: nothing occludes there.
    pub(crate) fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, scene: &GpuScene) {
        for view in &scene.shadow_views {
            let target = Target {
                extent: self.moments.desc.extent(),
                colors: [self.layer_views[view.layer as usize].raw],
                clear: [view.far, view.far * view.far, 0.0, 0.0],
                depth: self.depth.view,
            };
            let push = VsmPush { light: view.light, layer: view.layer };
            self.pass.record(rec, tracker, target, [(push, 0, scene.index_count)]);
        }
    }
}
