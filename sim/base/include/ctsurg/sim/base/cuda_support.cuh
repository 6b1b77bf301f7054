// What every CUDA launcher file of sim/ needs (nvcc only; included by *_cuda.cu files): checked CUDA
// calls that throw RuntimeError with the file and line (NVIDIA Warp's native code checks every call
// the same way), a launch check that debug builds turn into a synchronisation, an owning device
// array and a pinned host value, and the grid size of a one-thread-per-index launch.
//
// Errors: RuntimeError("file:line: call: cudaErrorName: description"). Destructors report a failed
// release on stderr and never throw.
#pragma once

#include "ctsurg/core/error.h"

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

// Throws RuntimeError unless `call` (a cudaError_t expression) succeeded.
#define CTSURG_CUDA_CHECK(call) ::ctsurg::sim::cuda::check((call), #call, __FILE__, __LINE__)
// After a kernel launch on `stream`: the launch error; in debug builds (NDEBUG undefined) also the
// kernel's own, by synchronising.
#if defined(NDEBUG)
#define CTSURG_CUDA_LAUNCHED(stream) CTSURG_CUDA_CHECK(cudaGetLastError())
#else
#define CTSURG_CUDA_LAUNCHED(stream) \
  (CTSURG_CUDA_CHECK(cudaGetLastError()), CTSURG_CUDA_CHECK(cudaStreamSynchronize(stream)))
#endif

namespace ctsurg::sim::cuda {

inline void check(cudaError_t error, const char* call, const char* file, int line) {
  if (error == cudaSuccess) return;
  throw RuntimeError(std::string(file) + ":" + std::to_string(line) + ": " + call + ": " + cudaGetErrorName(error) +
                     ": " + cudaGetErrorString(error));
}

// For destructors: reports a failed release (except at process exit, when the runtime is unloading).
inline void release_check(cudaError_t error, const char* call) {
  if (error != cudaSuccess && error != cudaErrorCudartUnloading)
    std::fprintf(stderr, "ctsurg: %s failed while releasing: %s\n", call, cudaGetErrorString(error));
}

// Blocks of `block` threads that cover n indices (one thread per index).
inline unsigned blocks_for(int64_t n, int block) { return static_cast<unsigned>((n + block - 1) / block); }

// An owning device array of a trivially copyable T (no construction).
template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  ~DeviceBuffer() { reset(); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;

  void reset() {
    if (data_ != nullptr) release_check(cudaFree(data_), "cudaFree");
    data_ = nullptr, size_ = 0;
  }
  // Reallocates only when n differs from the size (the pointer stays when it does not: captured
  // graphs that use the buffer stay valid).
  void resize(std::size_t n) {
    if (n == size_) return;
    reset();
    if (n > 0) CTSURG_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&data_), n * sizeof(T)));
    size_ = n;
  }
  // Resizes to n and queues a copy of n elements from host memory on `stream`; the host memory must
  // stay valid until the stream has run the copy.
  void upload(const T* host, std::size_t n, cudaStream_t stream) {
    resize(n);
    if (n > 0) CTSURG_CUDA_CHECK(cudaMemcpyAsync(data_, host, n * sizeof(T), cudaMemcpyHostToDevice, stream));
  }
  template <class V>
  void upload(const V& host, cudaStream_t stream) {
    upload(host.data(), host.size(), stream);
  }
  // Queues a copy of the first n elements into host memory on `stream`.
  void download(T* host, std::size_t n, cudaStream_t stream) const {
    if (n > 0) CTSURG_CUDA_CHECK(cudaMemcpyAsync(host, data_, n * sizeof(T), cudaMemcpyDeviceToHost, stream));
  }
  void zero(cudaStream_t stream) {
    if (size_ > 0) CTSURG_CUDA_CHECK(cudaMemsetAsync(data_, 0, size_ * sizeof(T), stream));
  }
  T* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// One T in pinned host memory: the target of small asynchronous read-backs (status words, scalars).
template <class T>
class PinnedValue {
 public:
  PinnedValue() { CTSURG_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&data_), sizeof(T))); }
  ~PinnedValue() { release_check(cudaFreeHost(data_), "cudaFreeHost"); }
  PinnedValue(const PinnedValue&) = delete;
  PinnedValue& operator=(const PinnedValue&) = delete;

  T* get() const { return data_; }
  T& operator*() const { return *data_; }
  T* operator->() const { return data_; }

 private:
  T* data_ = nullptr;
};

// A stream that is created with the object and destroyed (after its work) with it.
class Stream {
 public:
  Stream() { CTSURG_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking)); }
  ~Stream() {
    release_check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
    release_check(cudaStreamDestroy(stream_), "cudaStreamDestroy");
  }
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  operator cudaStream_t() const { return stream_; }
  void synchronize() const { CTSURG_CUDA_CHECK(cudaStreamSynchronize(stream_)); }

 private:
  cudaStream_t stream_ = nullptr;
};

// An instantiated CUDA graph (a recorded sequence of launches, replayed with one launch), or none.
class Graph {
 public:
  Graph() = default;
  ~Graph() { release(); }
  Graph(const Graph&) = delete;
  Graph& operator=(const Graph&) = delete;

  explicit operator bool() const { return exec_ != nullptr; }
  void release() {
    if (exec_ != nullptr) release_check(cudaGraphExecDestroy(exec_), "cudaGraphExecDestroy");
    exec_ = nullptr;
  }
  // Records what `launches()` queues on `stream` (nothing runs) and instantiates it, replacing the
  // previous graph. If `launches` throws, the capture is ended and the exception passed on.
  template <class Launches>
  void capture(cudaStream_t stream, const Launches& launches) {
    release();
    cudaGraph_t graph = nullptr;
    CTSURG_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
    try {
      launches();
    } catch (...) {
      (void)cudaStreamEndCapture(stream, &graph);
      if (graph != nullptr) (void)cudaGraphDestroy(graph);
      throw;
    }
    CTSURG_CUDA_CHECK(cudaStreamEndCapture(stream, &graph));
    const cudaError_t made = cudaGraphInstantiate(&exec_, graph, 0);
    CTSURG_CUDA_CHECK(cudaGraphDestroy(graph));
    CTSURG_CUDA_CHECK(made);
  }
  void launch(cudaStream_t stream) const { CTSURG_CUDA_CHECK(cudaGraphLaunch(exec_, stream)); }

 private:
  cudaGraphExec_t exec_ = nullptr;
};

// Makes device `ordinal` current for the calling host thread.
inline void use_device(int ordinal) { CTSURG_CUDA_CHECK(cudaSetDevice(ordinal)); }

}  // namespace ctsurg::sim::cuda
