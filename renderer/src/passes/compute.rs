//! The one shape of a compute pass. A pass names, once at creation, every resource its shader
//! binds and how the shader uses it ([`Slot`]); each dispatch then declares those uses to the
//! tracker (which records the barriers), binds, pushes the constants and dispatches. A pass
//! with several descriptor sets of one layout (ping-pong passes) picks one per dispatch.

use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Image, Pipeline, Sampler, Tracker};
use crate::vk::{Buffer, Use, VkResult};
use bytemuck::NoUninit;
use std::sync::Arc;

/// A resource bound to a compute shader and how the shader uses it.
pub enum Slot<'r> {
    /// A storage buffer used as `access` (ComputeStorageRead, -Write or -ReadWrite).
    Buffer(&'r Buffer, Access),
    /// A storage buffer the frame rewrites in its command stream before any pass (the lights
    /// and shadow layers, `GpuScene::record_updates`), whose barriers come with that update,
    /// or the host writes while no frame is in flight (the vertex buffer as meshes move).
    Updated(&'r Buffer),
    /// The frame's uniform buffer, rewritten the same way.
    Uniform(&'r Buffer),
    /// A storage image used as `access`.
    StorageImage(&'r Image, Access),
    /// An image sampled through `sampler`.
    Sampled(&'r Image, &'r Sampler),
}

impl Slot<'_> {
    fn binding(&self) -> Binding {
        match self {
            Slot::Buffer(buffer, _) | Slot::Updated(buffer) => Binding::StorageBuffer(buffer.raw),
            Slot::Uniform(buffer) => Binding::UniformBuffer(buffer.raw),
            Slot::StorageImage(image, _) => Binding::StorageImage(image.view),
            Slot::Sampled(image, sampler) => Binding::SampledImage { view: image.view, sampler: sampler.raw },
        }
    }

    fn tracked(&self) -> Option<Use> {
        match self {
            Slot::Buffer(buffer, access) => Some(Use::Buffer((*buffer).into(), *access)),
            Slot::StorageImage(image, access) => Some(Use::Image((*image).into(), *access)),
            Slot::Sampled(image, _) => Some(Use::Image((*image).into(), Access::ComputeSampled)),
            Slot::Updated(_) | Slot::Uniform(_) => None,
        }
    }
}

pub struct ComputePass {
    pipeline: Pipeline,
    sets: Vec<(DescriptorSet, Vec<Use>)>,
}

impl ComputePass {
    /// A pass of one descriptor set.
    pub fn new(ctx: &Arc<Context>, spirv: &[u8], push_bytes: u32, slots: &[Slot]) -> VkResult<ComputePass> {
        ComputePass::with_sets(ctx, spirv, push_bytes, &[slots])
    }

    /// A pass whose dispatches each bind one of `sets` (all with the same kinds of bindings).
    pub fn with_sets(ctx: &Arc<Context>, spirv: &[u8], push_bytes: u32, sets: &[&[Slot]]) -> VkResult<ComputePass> {
        let mut made = Vec::with_capacity(sets.len());
        for slots in sets {
            let bindings: Vec<Binding> = slots.iter().map(Slot::binding).collect();
            let set = DescriptorSet::new(ctx, vk::ShaderStageFlags::COMPUTE, &bindings)?;
            made.push((set, slots.iter().filter_map(Slot::tracked).collect()));
        }
        let pipeline = Pipeline::compute(ctx, spirv, made[0].0.layout, push_bytes)?;
        Ok(ComputePass { pipeline, sets: made })
    }

    /// Declares set `set`'s uses, binds it and dispatches `groups` workgroups with `push` as
    /// the push constants (none for a zero-sized type). Allocates nothing.
    pub fn dispatch<P: NoUninit>(&self, rec: &CommandRecorder, tracker: &mut Tracker, set: usize, push: &P, groups: [u32; 3]) {
        let (descriptors, uses) = &self.sets[set];
        tracker.declare(rec, uses);
        rec.bind_compute(self.pipeline.raw, self.pipeline.layout, descriptors.set);
        if std::mem::size_of::<P>() > 0 {
            rec.push_constants(self.pipeline.layout, push);
        }
        rec.dispatch(groups[0], groups[1], groups[2]);
    }
}

/// Workgroups of 8 x 8 (x one layer) covering an image: the grid of every per-texel pass.
pub fn per_texel(image: &Image) -> [u32; 3] {
    [image.desc.width.div_ceil(8), image.desc.height.div_ceil(8), image.desc.layers]
}
