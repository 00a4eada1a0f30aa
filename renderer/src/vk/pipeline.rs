//! Compute and graphics pipelines from embedded SPIR-V, with their layouts, destroyed on drop.
//! Graphics pipelines use dynamic rendering (no render passes) and dynamic viewport and scissor.
//! Specialization constants pick a shader's variant at creation (constant_id i = value i).
//! Every pipeline is made for its pass's descriptor set and push block only after its shaders'
//! SPIR-V says they agree (`reflect.rs`); a compute pipeline keeps its workgroup size.

use super::reflect::{check, reflect};
use super::{Context, DescriptorSet, VkError, VkResult};
use ash::vk;
use std::sync::Arc;

/// A shader module that lives only while a pipeline is created from it.
struct ShaderModule<'a> {
    ctx: &'a Context,
    raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    fn new(ctx: &'a Context, spirv: &[u8]) -> VkResult<Self> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| VkError::Invalid(format!("embedded SPIR-V is malformed: {e}")))?;
        // SAFETY: the words are SPIR-V produced by shaderc at build time.
        let raw = unsafe { ctx.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }?;
        Ok(ShaderModule { ctx, raw })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: a module may be destroyed once pipelines are created from it.
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}

/// u32 specialization constants: constant_id i takes `values[i]`.
struct Specialization {
    entries: Vec<vk::SpecializationMapEntry>,
    data: Vec<u8>,
}

impl Specialization {
    fn new(values: &[u32]) -> Self {
        let entries = (0..values.len() as u32).map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 }).collect();
        Specialization { entries, data: values.iter().flat_map(|v| v.to_le_bytes()).collect() }
    }

    fn info(&self) -> vk::SpecializationInfo<'_> {
        vk::SpecializationInfo::default().map_entries(&self.entries).data(&self.data)
    }
}

/// A compute or graphics pipeline with its layout (one descriptor set, push constants
/// visible to every stage).
pub struct Pipeline {
    ctx: Arc<Context>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    /// A compute shader's workgroup size, as its SPIR-V declares it ([1, 1, 1] for graphics).
    pub local_size: [u32; 3],
}

pub struct GraphicsPipelineDesc<'a> {
    /// The pass's name, for refusals.
    pub name: &'a str,
    pub vertex: &'a [u8],
    pub fragment: &'a [u8],
    /// Specialization constants of both stages.
    pub specialization: &'a [u32],
    pub vertex_stride: u32,
    pub attributes: &'a [vk::VertexInputAttributeDescription],
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    pub cull_mode: vk::CullModeFlags,
    /// The pass's descriptor set: both stages' bindings are checked against its kinds.
    pub set: &'a DescriptorSet,
    pub push_bytes: u32,
}

impl Pipeline {
    /// The pipeline layout alone; the pipeline is filled in by the caller (drop cleans up both).
    fn with_layout(ctx: &Arc<Context>, set_layout: vk::DescriptorSetLayout, push_bytes: u32) -> VkResult<Self> {
        let set_layouts = [set_layout];
        let ranges = [vk::PushConstantRange { stage_flags: vk::ShaderStageFlags::ALL, offset: 0, size: push_bytes }];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(if push_bytes > 0 {
            &ranges
        } else {
            &[]
        });
        // SAFETY: a valid create info on a live device.
        let layout = unsafe { ctx.device.create_pipeline_layout(&info, None) }?;
        Ok(Pipeline { ctx: Arc::clone(ctx), raw: vk::Pipeline::null(), layout, local_size: [1; 3] })
    }

    /// The compute pipeline of pass `name`. Refused, naming the pass and the binding: a shader
    /// whose bindings or push block disagree with `set` and `push_bytes`.
    pub fn compute(ctx: &Arc<Context>, name: &str, spirv: &[u8], set: &DescriptorSet, push_bytes: u32) -> VkResult<Self> {
        let interface = reflect(name, spirv)?;
        check(name, &[&interface], &set.kinds, push_bytes)?;
        let mut pipeline = Pipeline::with_layout(ctx, set.layout, push_bytes)?;
        pipeline.local_size = interface.local_size.unwrap_or([1; 3]);
        let module = ShaderModule::new(ctx, spirv)?;
        let stage = vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module.raw).name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(pipeline.layout)];
        // SAFETY: module and layout are live for the call.
        let created = unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
        pipeline.raw = created.map_err(|(_, e)| e)?[0];
        Ok(pipeline)
    }

    /// The graphics pipeline of `desc`; refused like [`Pipeline::compute`].
    pub fn graphics(ctx: &Arc<Context>, desc: &GraphicsPipelineDesc) -> VkResult<Self> {
        let stages = [reflect(desc.name, desc.vertex)?, reflect(desc.name, desc.fragment)?];
        check(desc.name, &[&stages[0], &stages[1]], &desc.set.kinds, desc.push_bytes)?;
        let mut pipeline = Pipeline::with_layout(ctx, desc.set.layout, desc.push_bytes)?;
        let vertex = ShaderModule::new(ctx, desc.vertex)?;
        let fragment = ShaderModule::new(ctx, desc.fragment)?;
        let specialization = Specialization::new(desc.specialization);
        let specialization_info = specialization.info();
        let stage = |stage, module| {
            vk::PipelineShaderStageCreateInfo::default().stage(stage).module(module).name(c"main").specialization_info(&specialization_info)
        };
        let stages = [stage(vk::ShaderStageFlags::VERTEX, vertex.raw), stage(vk::ShaderStageFlags::FRAGMENT, fragment.raw)];
        let bindings =
            [vk::VertexInputBindingDescription::default().binding(0).stride(desc.vertex_stride).input_rate(vk::VertexInputRate::VERTEX)];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(desc.attributes);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
        let attachments: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(pipeline.layout)
            .push_next(&mut rendering)];
        // SAFETY: every state struct, the specialization data and both modules outlive the call.
        let created = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        pipeline.raw = created.map_err(|(_, e)| e)?[0];
        Ok(pipeline)
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the pipeline; a null pipeline is a no-op.
        unsafe {
            self.ctx.device.destroy_pipeline(self.raw, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}
