//! Buffers with their allocations. Host-visible ones are written and read through their mapping.

use super::{Context, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    pub fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> VkResult<Buffer> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_buffer(&info, None) }?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and unbound.
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(e.into());
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements and is bound once.
        unsafe { ctx.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }?;
        Ok(Buffer { raw, size, allocation: Some(allocation) })
    }

    /// A host-visible storage buffer holding `data`.
    pub fn with_data<T: Copy>(ctx: &Context, name: &str, usage: vk::BufferUsageFlags, data: &[T]) -> VkResult<Buffer> {
        let bytes = std::mem::size_of_val(data) as u64;
        let buffer = Buffer::new(ctx, name, bytes, usage, MemoryLocation::CpuToGpu)?;
        buffer.write(data)?;
        Ok(buffer)
    }

    fn mapped(&self) -> VkResult<&mut [u8]> {
        let allocation = self.allocation.as_ref().ok_or_else(|| VkError::Invalid("buffer freed".into()))?;
        let ptr = allocation
            .mapped_ptr()
            .ok_or_else(|| VkError::Invalid("buffer is not host visible".into()))?;
        // SAFETY: the mapping covers `allocation.size()` bytes and lives as long as `self`;
        // callers synchronise with the GPU (fences) before touching it.
        Ok(unsafe { std::slice::from_raw_parts_mut(ptr.as_ptr() as *mut u8, allocation.size() as usize) })
    }

    /// Copies `data` to the start of a host-visible buffer.
    pub fn write<T: Copy>(&self, data: &[T]) -> VkResult<()> {
        let bytes = std::mem::size_of_val(data);
        let target = self.mapped()?;
        if bytes > target.len() {
            return Err(VkError::Invalid(format!("{bytes} bytes do not fit a {}-byte buffer", target.len())));
        }
        // SAFETY: `data` is plain Copy data of `bytes` bytes; the ranges do not overlap.
        unsafe { std::ptr::copy_nonoverlapping(data.as_ptr() as *const u8, target.as_mut_ptr(), bytes) };
        Ok(())
    }

    /// Reads the first `len` bytes of a host-visible buffer.
    pub fn read_bytes(&self, len: usize) -> VkResult<Vec<u8>> {
        let source = self.mapped()?;
        source.get(..len).map(<[u8]>::to_vec).ok_or_else(|| VkError::Invalid("read past buffer".into()))
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(allocation) = self.allocation.take() {
            // SAFETY: the caller guarantees the GPU no longer uses the buffer.
            unsafe { ctx.device.destroy_buffer(self.raw, None) };
            let _ = ctx.allocator().free(allocation);
        }
    }
}
