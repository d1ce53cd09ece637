//! GPU buffers kept from frame to frame: grown (to the next power of two) when a frame needs
//! more, never shrunk, so a steady stream of frames allocates nothing.

/// A buffer of at least the size last asked for.
#[derive(Debug)]
pub struct GrowBuffer {
    label: &'static str,
    usage: wgpu::BufferUsages,
    buffer: wgpu::Buffer,
}

/// The smallest buffer made: a binding may not be empty.
const MIN_BYTES: u64 = 256;

impl GrowBuffer {
    /// An empty buffer of `usage` (COPY_DST is added).
    pub fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        GrowBuffer {
            label,
            usage,
            buffer: make(device, label, usage, MIN_BYTES),
        }
    }

    /// Writes `bytes` at the start, growing the buffer first if it is too small. Returns true
    /// when the buffer was replaced (bind groups that hold it must be made again).
    pub fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8]) -> bool {
        let grown = self.reserve(device, bytes.len() as u64);
        if !bytes.is_empty() {
            queue.write_buffer(&self.buffer, 0, bytes);
        }
        grown
    }

    /// Makes room for `len` bytes; true when the buffer was replaced.
    pub fn reserve(&mut self, device: &wgpu::Device, len: u64) -> bool {
        if len <= self.buffer.size() {
            return false;
        }
        let size = len.next_power_of_two().max(MIN_BYTES);
        self.buffer = make(device, self.label, self.usage, size);
        true
    }

    /// The buffer.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }
}

fn make(
    device: &wgpu::Device,
    label: &'static str,
    usage: wgpu::BufferUsages,
    size: u64,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}
