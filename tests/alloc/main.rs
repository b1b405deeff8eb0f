//! Allocation counts, one binary with one counting global allocator: the core, the SVDs, the decoder and the daemon's hot paths allocate nothing.

mod alloc_free;
mod counting_alloc;
mod daemon_alloc;
mod perf_alloc;
mod protocol_alloc;
mod svd_alloc;
