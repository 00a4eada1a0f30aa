//! Timestamp queries: two per pass, read back after the frame's fence.

use super::{CommandRecorder, Context, VkResult};
use ash::vk;

pub struct TimestampQueries {
    pool: vk::QueryPool,
    capacity: u32,
    period_ns: f64,
}

impl TimestampQueries {
    /// None when the device cannot write timestamps (the frame then reports no pass times).
    pub fn new(ctx: &Context, capacity: u32) -> VkResult<Option<Self>> {
        let Some(period_ns) = ctx.info.timestamp_period_ns else { return Ok(None) };
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: a valid create info on a live device.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Some(TimestampQueries { pool, capacity, period_ns }))
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn reset(&self, rec: &CommandRecorder) {
        // SAFETY: recording state; the range lies in the pool.
        unsafe { rec.device.cmd_reset_query_pool(rec.cmd, self.pool, 0, self.capacity) };
    }

    /// Writes timestamp `index` once all earlier commands have finished.
    pub fn write(&self, rec: &CommandRecorder, index: u32) {
        // SAFETY: recording state; the index was reset in this command buffer.
        unsafe { rec.device.cmd_write_timestamp2(rec.cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, index) };
    }

    /// The first `count` timestamps in milliseconds, after the frame's fence has signalled.
    pub fn read_ms(&self, ctx: &Context, count: u32) -> VkResult<Vec<f64>> {
        let mut ticks = vec![0u64; count as usize];
        // SAFETY: the queries were written by a submission that has completed.
        unsafe { ctx.device.get_query_pool_results(self.pool, 0, &mut ticks, vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT) }?;
        Ok(ticks.iter().map(|t| *t as f64 * self.period_ns * 1e-6).collect())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU no longer uses the pool.
        unsafe { ctx.device.destroy_query_pool(self.pool, None) };
    }
}
