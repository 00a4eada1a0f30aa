//! Timestamp queries: one before the first pass and one after each, read after the frame's fence.

use super::{CommandRecorder, Context, VkResult};
use ash::vk;

pub struct TimestampQueries<'a> {
    ctx: &'a Context,
    pool: vk::QueryPool,
    period_ns: f64,
}

impl<'a> TimestampQueries<'a> {
    pub const CAPACITY: usize = 16;

    /// None when the device cannot write timestamps (the frame then reports no pass times).
    pub fn new(ctx: &'a Context) -> VkResult<Option<Self>> {
        let Some(period_ns) = ctx.info.timestamp_period_ns else { return Ok(None) };
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(Self::CAPACITY as u32);
        // SAFETY: a valid create info on a live device.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Some(TimestampQueries { ctx, pool, period_ns }))
    }

    pub fn reset(&self, rec: &CommandRecorder) {
        // SAFETY: recording state; the range lies in the pool.
        unsafe { rec.device.cmd_reset_query_pool(rec.cmd, self.pool, 0, Self::CAPACITY as u32) };
    }

    /// Writes timestamp `index` once all earlier commands have finished.
    pub fn write(&self, rec: &CommandRecorder, index: u32) {
        // SAFETY: recording state; the index was reset in this command buffer.
        unsafe { rec.device.cmd_write_timestamp2(rec.cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, index) };
    }

    /// The first N timestamps in milliseconds, after the frame's fence has signalled.
    pub fn read_ms<const N: usize>(&self) -> VkResult<[f64; N]> {
        let mut ticks = [0u64; N];
        // SAFETY: the queries were written by a submission that has completed.
        unsafe {
            self.ctx.device.get_query_pool_results(self.pool, 0, &mut ticks, vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT)
        }?;
        Ok(ticks.map(|t| t as f64 * self.period_ns * 1e-6))
    }
}

impl Drop for TimestampQueries<'_> {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
