// The contact queries on a CUDA device (collision_backends.h): the spatial hash built and queried on the
// device from the CPU's per-index functions (kernels/spatial_hash_impl.h, contact_tests_impl.h), compiled
// with -fmad=false (sim/CMakeLists.txt) so that the doubles, and therefore the contacts, are the CPU's.
//
// Passes (one thread per primitive, bucket or vertex; all on one stream):
//   build: cell counts per primitive and their sum E (cub::DeviceReduce; read back: the table size n is
//          the smallest prime >= E, chosen on the host as on the CPU); bucket counts (atomicAdd); an
//          exclusive sum (cub::DeviceScan) to offsets; the fill at atomic cursors; each bucket sorted by
//          primitive index (the fill's order is the schedule's, the sorted table is not);
//   query: contacts per vertex; an exclusive sum; the total read back; the records written at each
//          vertex's offset, in the bucket's (sorted) order: sorted by (vertex, primitive), as on the CPU.
// Memory on the device: the inputs (positions, indices, object ids), per-primitive counts (8 #P bytes),
// the table (4 (n + 1) + 4 n + 4 E bytes), per-vertex offsets (8 (#V + 1) bytes) and the records.
#include "collision_backends.h"

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/cuda_support.cuh"

#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>

namespace ctsurg::sim::collision_detail {
namespace {

constexpr int kBlock = 256;

__device__ inline int64_t thread_index() { return static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; }

__global__ void __launch_bounds__(kBlock) cell_count_kernel(HashedPrimitivesView p, double cell_size, int64_t* counts) {
  const int64_t i = thread_index();
  if (i < p.count) counts[i] = cell_count(primitive_cells(p, cell_size, i));
}

__global__ void __launch_bounds__(kBlock) bucket_count_kernel(HashedPrimitivesView p, HashGridShape s, uint32_t* counts) {
  const int64_t i = thread_index();
  if (i < p.count) count_primitive<true>(p, s, counts, i);
}

__global__ void __launch_bounds__(kBlock) fill_kernel(HashedPrimitivesView p, HashGridShape s, const uint32_t* offsets,
                                                      uint32_t* cursors, uint32_t* entries) {
  const int64_t i = thread_index();
  if (i < p.count) fill_primitive<true>(p, s, offsets, cursors, entries, i);
}

__global__ void __launch_bounds__(kBlock) sort_kernel(const uint32_t* offsets, uint32_t* entries, int64_t buckets) {
  const int64_t b = thread_index();
  if (b < buckets) sort_bucket(offsets, entries, b);
}

template <class Test, class Record>
__global__ void __launch_bounds__(kBlock) contact_count_kernel(HashTableView table, Test test, const double* positions,
                                                               int64_t vertices, int64_t* counts) {
  const int64_t v = thread_index();
  if (v < vertices) counts[v] = vertex_candidates<Test, Record>(table, positions, test, v, nullptr);
}

template <class Test, class Record>
__global__ void __launch_bounds__(kBlock) contact_write_kernel(HashTableView table, Test test, const double* positions,
                                                               int64_t vertices, const int64_t* offsets, Record* out) {
  const int64_t v = thread_index();
  if (v < vertices && offsets[v + 1] > offsets[v])
    vertex_candidates<Test, Record>(table, positions, test, v, out + offsets[v]);
}

// out[i] = sum of in[0, i) for i < n (cub::DeviceScan; temp grows as needed).
template <class T>
void exclusive_sum(const T* in, T* out, int64_t n, cuda::DeviceBuffer<unsigned char>& temp, cudaStream_t stream) {
  std::size_t bytes = 0;
  CTSURG_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, out, n, stream));
  if (bytes > temp.size()) temp.resize(bytes);
  CTSURG_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(temp.data(), bytes, in, out, n, stream));
}

// The sum of in[0, n), read back (synchronises the stream).
int64_t device_sum(const int64_t* in, int64_t n, cuda::DeviceBuffer<unsigned char>& temp, cudaStream_t stream) {
  cuda::DeviceBuffer<int64_t> sum;
  sum.resize(1);
  std::size_t bytes = 0;
  CTSURG_CUDA_CHECK(cub::DeviceReduce::Sum(nullptr, bytes, in, sum.data(), n, stream));
  if (bytes > temp.size()) temp.resize(bytes);
  CTSURG_CUDA_CHECK(cub::DeviceReduce::Sum(temp.data(), bytes, in, sum.data(), n, stream));
  int64_t host = 0;
  sum.download(&host, 1, stream);
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(stream));
  return host;
}

// The primitives a test hashes (its view is rewritten to device pointers).
HashedPrimitivesView& primitives_of(VertexTriangleTest& t) { return t.triangles; }
HashedPrimitivesView& primitives_of(VertexTetTest& t) { return t.tets; }

template <class Test, class Record>
std::vector<Record> run(Test test, int64_t vertices, double cell_size, const char* where) {
  require_backend(Backend::cuda, where);
  HashedPrimitivesView& p = primitives_of(test);
  if (vertices == 0 || p.count == 0) return {};
  cuda::use_device(0);
  cuda::Stream stream;
  cuda::DeviceBuffer<unsigned char> temp;

  // Inputs, and the test's views on the device.
  cuda::DeviceBuffer<double> positions;
  cuda::DeviceBuffer<uint32_t> indices, vertex_object, primitive_object;
  positions.upload(p.positions, 3 * static_cast<std::size_t>(vertices), stream);
  indices.upload(p.indices, static_cast<std::size_t>(p.count) * p.corners, stream);
  vertex_object.upload(test.filter.vertex_object, static_cast<std::size_t>(vertices), stream);
  primitive_object.upload(test.filter.primitive_object, static_cast<std::size_t>(p.count), stream);
  p.positions = positions.data(), p.indices = indices.data();
  test.filter.vertex_object = vertex_object.data(), test.filter.primitive_object = primitive_object.data();

  // Build.
  const unsigned primitive_blocks = cuda::blocks_for(p.count, kBlock);
  cuda::DeviceBuffer<int64_t> cell_counts;
  cell_counts.resize(static_cast<std::size_t>(p.count));
  cell_count_kernel<<<primitive_blocks, kBlock, 0, stream>>>(p, cell_size, cell_counts.data());
  CTSURG_CUDA_LAUNCHED(stream);
  const int64_t entries = device_sum(cell_counts.data(), p.count, temp, stream);
  check_entry_count(entries, where);
  const HashGridShape shape{cell_size, hash_table_size(entries)};
  const int64_t n = shape.table_size;
  cuda::DeviceBuffer<uint32_t> bucket_counts, offsets, cursors, table_entries;
  bucket_counts.resize(static_cast<std::size_t>(n + 1));
  bucket_counts.zero(stream);
  bucket_count_kernel<<<primitive_blocks, kBlock, 0, stream>>>(p, shape, bucket_counts.data());
  CTSURG_CUDA_LAUNCHED(stream);
  offsets.resize(static_cast<std::size_t>(n + 1));
  exclusive_sum(bucket_counts.data(), offsets.data(), n + 1, temp, stream);
  cursors.resize(static_cast<std::size_t>(n));
  cursors.zero(stream);
  table_entries.resize(static_cast<std::size_t>(entries));
  fill_kernel<<<primitive_blocks, kBlock, 0, stream>>>(p, shape, offsets.data(), cursors.data(), table_entries.data());
  CTSURG_CUDA_LAUNCHED(stream);
  sort_kernel<<<cuda::blocks_for(n, kBlock), kBlock, 0, stream>>>(offsets.data(), table_entries.data(), n);
  CTSURG_CUDA_LAUNCHED(stream);
  const HashTableView table{shape, offsets.data(), table_entries.data()};

  // Query: count, scan, write.
  const unsigned vertex_blocks = cuda::blocks_for(vertices, kBlock);
  cuda::DeviceBuffer<int64_t> counts, contact_offsets;
  counts.resize(static_cast<std::size_t>(vertices + 1));
  counts.zero(stream);
  contact_count_kernel<Test, Record>
      <<<vertex_blocks, kBlock, 0, stream>>>(table, test, positions.data(), vertices, counts.data());
  CTSURG_CUDA_LAUNCHED(stream);
  contact_offsets.resize(static_cast<std::size_t>(vertices + 1));
  exclusive_sum(counts.data(), contact_offsets.data(), vertices + 1, temp, stream);
  int64_t total = 0;
  CTSURG_CUDA_CHECK(cudaMemcpyAsync(&total, contact_offsets.data() + vertices, sizeof(int64_t), cudaMemcpyDeviceToHost,
                                    stream));
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(stream));
  std::vector<Record> out(static_cast<std::size_t>(total));
  if (total == 0) return out;
  cuda::DeviceBuffer<Record> records;
  records.resize(static_cast<std::size_t>(total));
  contact_write_kernel<Test, Record><<<vertex_blocks, kBlock, 0, stream>>>(table, test, positions.data(), vertices,
                                                                           contact_offsets.data(), records.data());
  CTSURG_CUDA_LAUNCHED(stream);
  records.download(out.data(), out.size(), stream);
  stream.synchronize();
  return out;
}

}  // namespace

std::vector<VertexTriangleContact> vertex_triangle_contacts_cuda(const VertexTriangleTest& test, int64_t vertices,
                                                                 double cell_size, const char* where) {
  return run<VertexTriangleTest, VertexTriangleContact>(test, vertices, cell_size, where);
}

std::vector<VertexTetContact> vertex_tet_contacts_cuda(const VertexTetTest& test, int64_t vertices, double cell_size,
                                                       const char* where) {
  return run<VertexTetTest, VertexTetContact>(test, vertices, cell_size, where);
}

}  // namespace ctsurg::sim::collision_detail
