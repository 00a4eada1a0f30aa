//! FIV's occluder sums (compute), 003 §5 per pixel: shaders/fiv/occluder_sums.comp, whose
//! CPU twin is relume_bake::fiv::FivBake::irradiance.
//!
//! Reads: `positions` and `normals` (its surfaces pass, or the engine's), DifMap, the tables, the types and
//! the occluders (rewritten in the command stream at the start of the pass, from the
//! technique's own array: no allocation). Writes: `irradiance` (RGBA32F, one layer; rgb lux,
//! 0 where no surface). Cost: per pixel one DifMap read and, per occluder not below the
//! surface (its own included, when self-shadowing), 8 table samples of 3 vec4, plus with the overlap correction a disc per other
//! occluder: O(pixels x occluders^2) arithmetic, O(pixels x occluders) table reads.

use super::Buffers;
use crate::passes::compute::{per_texel, ComputePass, Slot};
use crate::shaders;
use crate::technique::{Shared, Surfaces};
use crate::vk::{Access, CommandRecorder, Image, Tracker, VkResult};
use relume_bake::fiv::{Beyond, Radial, SelfShadow, SumOptions};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct OccluderSumsPush {
    occluder_count: u32,
    difmap_width: u32,
    partial: u32,
    overlap: u32,
    beyond_scale: u32,
    inverse_square: u32,
    self_shadow: u32,
}

impl OccluderSumsPush {
    pub fn new(occluder_count: u32, difmap_width: u32, options: SumOptions) -> Self {
        OccluderSumsPush {
            occluder_count,
            difmap_width,
            partial: options.partial as u32,
            overlap: options.overlap as u32,
            beyond_scale: (options.beyond == Beyond::Scale) as u32,
            inverse_square: (options.radial == Radial::InverseSquare) as u32,
            self_shadow: match options.self_shadow {
                SelfShadow::Off => 0,
                SelfShadow::Paper => 1,
                SelfShadow::Surface => 2,
            },
        }
    }
}

pub(super) struct OccluderSumsPass {
    pass: ComputePass<OccluderSumsPush>,
    grid: [u32; 3],
}

impl OccluderSumsPass {
    pub fn new(shared: &Shared, surfaces: Surfaces, buffers: &Buffers, irradiance: &Image) -> VkResult<OccluderSumsPass> {
        let slots = [
            Slot::StorageImage(surfaces.positions, Access::ComputeStorageRead),
            Slot::StorageImage(surfaces.normals, Access::ComputeStorageRead),
            Slot::StorageImage(irradiance, Access::ComputeStorageWrite),
            Slot::Buffer(&buffers.difmap, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.tables, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.types, Access::ComputeStorageRead),
            Slot::Updated(&buffers.occluders),
        ];
        let pass = ComputePass::new(shared.ctx, "fiv.occluder_sums", shaders::FIV_OCCLUDER_SUMS_COMP, &slots)?;
        Ok(OccluderSumsPass { pass, grid: per_texel(irradiance) })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, push: &OccluderSumsPush) {
        self.pass.dispatch(rec, tracker, 0, push, self.grid);
    }
}
