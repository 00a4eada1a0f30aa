//! The one shape of a compute pass. A pass is one value: its name, every resource its shader
//! binds with how the shader uses it ([`Slot`], named once at creation), its push block (the
//! type `P`) and its shader, whose SPIR-V is checked against all of them when the pipeline is
//! made (a mismatch is refused, naming the pass and the binding). Each dispatch declares the
//! uses to the tracker (which records the barriers), binds, pushes and dispatches enough of the
//! shader's workgroups, whose size comes from its SPIR-V, to cover the invocations asked for.
//! A pass with several descriptor sets of one layout (ping-pong passes) picks one per dispatch.

use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Image, Pipeline, Sampler, Tracker};
use crate::vk::{Buffer, Use, VkError, VkResult};
use bytemuck::NoUninit;
use std::marker::PhantomData;
use std::sync::Arc;

/// A resource bound to a shader and how the shader uses it.
pub enum Slot<'r> {
    /// A storage buffer used as `access` (ComputeStorageRead, -Write or -ReadWrite, or
    /// GraphicsStorageRead).
    Buffer(&'r Buffer, Access),
    /// A storage buffer the frame rewrites in its command stream before any pass (the lights
    /// and shadow layers, `GpuScene::record_updates`), whose barriers come with that update,
    /// or the host writes while no frame is in flight (the vertex buffer as meshes move).
    Updated(&'r Buffer),
    /// The frame's uniform buffer, rewritten the same way.
    Uniform(&'r Buffer),
    /// A storage image used as `access`.
    StorageImage(&'r Image, Access),
    /// An image sampled through `sampler` (by the compute shader, or by a graphics pass's
    /// fragment stage).
    Sampled(&'r Image, &'r Sampler),
}

/// Which kind of pass samples a `Slot::Sampled` image.
#[derive(Clone, Copy)]
pub(crate) enum Sampling {
    Compute,
    Fragment,
}

impl Slot<'_> {
    pub(crate) fn binding(&self) -> Binding {
        match self {
            Slot::Buffer(buffer, _) | Slot::Updated(buffer) => Binding::StorageBuffer(buffer.raw),
            Slot::Uniform(buffer) => Binding::UniformBuffer(buffer.raw),
            Slot::StorageImage(image, _) => Binding::StorageImage(image.view),
            Slot::Sampled(image, sampler) => Binding::SampledImage { view: image.view, sampler: sampler.raw },
        }
    }

    pub(crate) fn tracked(&self, sampling: Sampling) -> Option<Use> {
        let sampled = match sampling {
            Sampling::Compute => Access::ComputeSampled,
            Sampling::Fragment => Access::FragmentSampled,
        };
        match self {
            Slot::Buffer(buffer, access) => Some(Use::buffer(*buffer, *access)),
            Slot::StorageImage(image, access) => Some(Use::image(*image, *access)),
            Slot::Sampled(image, _) => Some(Use::image(*image, sampled)),
            Slot::Updated(_) | Slot::Uniform(_) => None,
        }
    }
}

/// A compute pass whose push block is a `P` (`()` for none).
pub struct ComputePass<P = ()> {
    pipeline: Pipeline,
    sets: Vec<(DescriptorSet, Vec<Use>)>,
    push: PhantomData<P>,
}

impl<P: NoUninit> ComputePass<P> {
    /// Pass `name` of one descriptor set.
    pub fn new(ctx: &Arc<Context>, name: &str, spirv: &[u8], slots: &[Slot]) -> VkResult<Self> {
        ComputePass::with_sets(ctx, name, spirv, &[slots])
    }

    /// Pass `name`, whose dispatches each bind one of `sets` (all with the same kinds of
    /// bindings). Refused, naming the pass and the binding: no set, sets of other kinds, a
    /// shader that binds another kind at a slot's binding, binds what no slot gives, or whose
    /// push block is not a `P`.
    pub fn with_sets(ctx: &Arc<Context>, name: &str, spirv: &[u8], sets: &[&[Slot]]) -> VkResult<Self> {
        let mut made: Vec<(DescriptorSet, Vec<Use>)> = Vec::with_capacity(sets.len());
        for (i, slots) in sets.iter().enumerate() {
            let bindings: Vec<Binding> = slots.iter().map(Slot::binding).collect();
            let set = DescriptorSet::new(ctx, vk::ShaderStageFlags::COMPUTE, &bindings)?;
            if let Some((first, _)) = made.first().filter(|(first, _)| first.kinds != set.kinds) {
                return Err(VkError::Invalid(format!(
                    "pass {name}: set {i} binds {:?}, but set 0 binds {:?}; every set of a pass binds the same kinds",
                    set.kinds, first.kinds
                )));
            }
            made.push((set, slots.iter().filter_map(|s| s.tracked(Sampling::Compute)).collect()));
        }
        let Some((first, _)) = made.first() else {
            return Err(VkError::Invalid(format!("pass {name}: no descriptor set to bind")));
        };
        let pipeline = Pipeline::compute(ctx, name, spirv, first, std::mem::size_of::<P>() as u32)?;
        Ok(ComputePass { pipeline, sets: made, push: PhantomData })
    }

    /// Declares set `set`'s uses, binds it and dispatches the workgroups that cover
    /// `invocations` with `push` as the push constants. Allocates nothing.
    pub fn dispatch(&self, rec: &CommandRecorder, tracker: &mut Tracker, set: usize, push: &P, invocations: [u32; 3]) {
        let size = self.pipeline.local_size;
        self.dispatch_groups(rec, tracker, set, push, [0, 1, 2].map(|axis| invocations[axis].div_ceil(size[axis])));
    }

    /// As [`ComputePass::dispatch`], for a pass whose work items are workgroups: `groups` of
    /// them.
    pub fn dispatch_groups(&self, rec: &CommandRecorder, tracker: &mut Tracker, set: usize, push: &P, groups: [u32; 3]) {
        let (descriptors, uses) = &self.sets[set];
        tracker.pass(rec, uses.iter().copied(), |rec| {
            rec.bind_compute(self.pipeline.raw, self.pipeline.layout, descriptors.set);
            if std::mem::size_of::<P>() > 0 {
                rec.push_constants(self.pipeline.layout, push);
            }
            rec.dispatch(groups[0], groups[1], groups[2]);
        });
    }
}

/// One invocation per texel of every layer of `image`: the grid of every per-texel pass.
pub fn per_texel(image: &Image) -> [u32; 3] {
    [image.desc.width, image.desc.height, image.desc.layers]
}
