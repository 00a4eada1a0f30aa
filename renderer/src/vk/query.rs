//! Timestamp queries: one before the first pass and one after each, read once the frame's
//! submission has completed.

use super::{CommandRecorder, Context, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct TimestampQueries {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    period_ns: f64,
}

impl TimestampQueries {
    pub const CAPACITY: usize = 32;

    /// None when the device cannot write timestamps (the frame then reports no pass times).
    pub fn new(ctx: &Arc<Context>) -> VkResult<Option<Self>> {
        let Some(period_ns) = ctx.info.timestamp_period_ns else { return Ok(None) };
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(Self::CAPACITY as u32);
        // SAFETY: a valid create info on a live device.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Some(TimestampQueries { ctx: Arc::clone(ctx), pool, period_ns }))
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

    /// The first `out.len()` timestamps in milliseconds, once the submission that wrote them
    /// has completed; never waits (Err NOT_READY while it has not).
    pub fn read_ms(&self, out: &mut [f64]) -> VkResult<()> {
        let mut ticks = [0u64; Self::CAPACITY];
        let ticks = &mut ticks[..out.len().min(Self::CAPACITY)];
        // SAFETY: the queries were reset and written by a recorded submission.
        unsafe { self.ctx.device.get_query_pool_results(self.pool, 0, ticks, vk::QueryResultFlags::TYPE_64) }?;
        for (ms, t) in out.iter_mut().zip(ticks.iter()) {
            *ms = *t as f64 * self.period_ns * 1e-6;
        }
        Ok(())
    }
}

impl Drop for TimestampQueries {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
