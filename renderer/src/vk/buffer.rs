//! Buffers with their allocations, freed on drop. Host-visible ones are written and read
//! through their mapping.

use super::{Context, VkError, VkResult};
use ash::vk;
use bytemuck::NoUninit;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct Buffer {
    ctx: Arc<Context>,
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation) -> VkResult<Buffer> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_buffer(&info, None) }?;
        let mut buffer = Buffer { ctx: Arc::clone(ctx), raw, size, allocation: None };
        // SAFETY: a plain query of the buffer just made.
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: the allocation was made for this buffer's requirements and is bound once;
        // it is stored first so that drop frees it if binding fails.
        let (memory, offset) = unsafe { (allocation.memory(), allocation.offset()) };
        buffer.allocation = Some(allocation);
        unsafe { ctx.device.bind_buffer_memory(raw, memory, offset) }?;
        Ok(buffer)
    }

    /// A host-visible buffer holding `data`.
    pub fn with_data<T: NoUninit>(ctx: &Arc<Context>, name: &str, usage: vk::BufferUsageFlags, data: &[T]) -> VkResult<Self> {
        let bytes = std::mem::size_of_val(data) as u64;
        let buffer = Buffer::new(ctx, name, bytes, usage, MemoryLocation::CpuToGpu)?;
        buffer.write(data)?;
        Ok(buffer)
    }

    fn mapping(&self) -> VkResult<(*mut u8, usize)> {
        let allocation = self.allocation.as_ref().ok_or_else(|| VkError::Invalid("buffer has no memory".into()))?;
        let ptr = allocation.mapped_ptr().ok_or_else(|| VkError::Invalid("buffer is not host visible".into()))?;
        Ok((ptr.as_ptr() as *mut u8, allocation.size() as usize))
    }

    /// Copies `data` to the start of a host-visible buffer. The caller makes sure no GPU
    /// work that reads the buffer is pending.
    pub fn write<T: NoUninit>(&self, data: &[T]) -> VkResult<()> {
        self.write_at(0, data)
    }

    /// Copies `data` into a host-visible buffer from byte `offset` on; as [`Buffer::write`].
    pub fn write_at<T: NoUninit>(&self, offset: usize, data: &[T]) -> VkResult<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let (ptr, len) = self.mapping()?;
        if offset.checked_add(bytes.len()).is_none_or(|end| end > len) {
            return Err(VkError::Invalid(format!("{} bytes at {offset} do not fit a {len}-byte buffer", bytes.len())));
        }
        // SAFETY: the mapping holds `len` >= offset + bytes.len() bytes and does not overlap `data`.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr.add(offset), bytes.len()) };
        Ok(())
    }

    /// The first `len` bytes of a host-visible buffer, after the GPU's writes to it completed.
    pub fn mapped_bytes(&self, len: usize) -> VkResult<&[u8]> {
        let (ptr, available) = self.mapping()?;
        if len > available {
            return Err(VkError::Invalid(format!("read of {len} bytes past a {available}-byte buffer")));
        }
        // SAFETY: the mapping is valid for `available` bytes as long as `self` lives, and the
        // caller waited for the GPU writes (fence), so nothing writes it meanwhile.
        Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the buffer (owners wait for their fences first).
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
        if let Some(allocation) = self.allocation.take() {
            let _ = self.ctx.allocator().free(allocation);
        }
    }
}
