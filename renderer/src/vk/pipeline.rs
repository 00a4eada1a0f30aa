//! Compute and graphics pipelines from embedded SPIR-V, with their layouts. Graphics pipelines
//! use dynamic rendering (no render passes) and dynamic viewport and scissor.

use super::{Context, VkError, VkResult};
use ash::vk;

fn shader_module(ctx: &Context, spirv: &[u8]) -> VkResult<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| VkError::Invalid(format!("embedded SPIR-V is malformed: {e}")))?;
    // SAFETY: the words are SPIR-V produced by shaderc at build time.
    Ok(unsafe { ctx.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }?)
}

fn pipeline_layout(ctx: &Context, set_layout: vk::DescriptorSetLayout, push_bytes: u32) -> VkResult<vk::PipelineLayout> {
    let set_layouts = [set_layout];
    let ranges = [vk::PushConstantRange { stage_flags: vk::ShaderStageFlags::ALL, offset: 0, size: push_bytes }];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&set_layouts)
        .push_constant_ranges(if push_bytes > 0 { &ranges } else { &[] });
    // SAFETY: a valid create info on a live device.
    Ok(unsafe { ctx.device.create_pipeline_layout(&info, None) }?)
}

pub struct ComputePipeline {
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
}

impl ComputePipeline {
    pub fn new(ctx: &Context, spirv: &[u8], set_layout: vk::DescriptorSetLayout, push_bytes: u32) -> VkResult<Self> {
        let layout = pipeline_layout(ctx, set_layout, push_bytes)?;
        let module = shader_module(ctx, spirv)?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
        // SAFETY: module and layout are live; the module may be destroyed once the pipeline exists.
        let result = unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
        unsafe { ctx.device.destroy_shader_module(module, None) };
        let raw = result.map_err(|(_, e)| e)?[0];
        Ok(ComputePipeline { raw, layout })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU no longer uses the pipeline.
        unsafe {
            ctx.device.destroy_pipeline(self.raw, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

pub struct GraphicsPipelineDesc<'a> {
    pub vertex: &'a [u8],
    pub fragment: &'a [u8],
    pub vertex_stride: u32,
    pub attributes: &'a [vk::VertexInputAttributeDescription],
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    pub cull_mode: vk::CullModeFlags,
    pub set_layout: vk::DescriptorSetLayout,
    pub push_bytes: u32,
    /// Fragment specialization constants: `constant_id = i` takes `fragment_constants[i]`.
    pub fragment_constants: &'a [u32],
}

pub struct GraphicsPipeline {
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
}

impl GraphicsPipeline {
    pub fn new(ctx: &Context, desc: &GraphicsPipelineDesc) -> VkResult<Self> {
        let layout = pipeline_layout(ctx, desc.set_layout, desc.push_bytes)?;
        let vertex = shader_module(ctx, desc.vertex)?;
        let fragment = shader_module(ctx, desc.fragment)?;
        let entries: Vec<_> = (0..desc.fragment_constants.len())
            .map(|i| vk::SpecializationMapEntry { constant_id: i as u32, offset: 4 * i as u32, size: 4 })
            .collect();
        let constant_bytes: Vec<u8> = desc.fragment_constants.iter().flat_map(|c| c.to_ne_bytes()).collect();
        let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(&constant_bytes);
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vertex).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fragment)
                .name(c"main")
                .specialization_info(&specialization),
        ];
        let bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(desc.vertex_stride)
            .input_rate(vk::VertexInputRate::VERTEX)];
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
            .layout(layout)
            .push_next(&mut rendering)];
        // SAFETY: every state struct outlives the call; modules are destroyed after it.
        let result = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        unsafe {
            ctx.device.destroy_shader_module(vertex, None);
            ctx.device.destroy_shader_module(fragment, None);
        }
        let raw = result.map_err(|(_, e)| e)?[0];
        Ok(GraphicsPipeline { raw, layout })
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU no longer uses the pipeline.
        unsafe {
            ctx.device.destroy_pipeline(self.raw, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}
