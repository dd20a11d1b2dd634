#include "backend/backend.h"

#include "backend/cpu/cpu_backend.h"
#include "core/error.h"
#ifdef UVR_HAVE_CUDA
#include "backend/cuda/cuda_backend.h"
#endif

namespace uvr {

const char *backendName(Backend backend) { return backend == Backend::Cuda ? "cuda" : "cpu"; }

#ifdef UVR_HAVE_CUDA
constexpr bool kCudaBuilt = true;
#else
constexpr bool kCudaBuilt = false;
#endif

bool backendBuilt(Backend backend) { return backend == Backend::Cpu || kCudaBuilt; }

Backend parseBackend(const std::string &name) {
  if (name == "cpu")
    return Backend::Cpu;
  if (name == "cuda") {
    if (!backendBuilt(Backend::Cuda))
      throw Error(
          "this uvr was built without CUDA (no CUDA toolkit was found at build time): use --backend cpu");
    return Backend::Cuda;
  }
  throw Error("unknown backend '" + name + "': expected cpu or cuda");
}

std::unique_ptr<RenderBackend> makeBackend(Backend backend, const Mesh &mesh, const MeshView &view,
                                           uint32_t leafSize) {
  if (backend == Backend::Cpu)
    return std::make_unique<CpuBackend>(mesh, view, leafSize);
#ifdef UVR_HAVE_CUDA
  return std::make_unique<CudaBackend>(view, mesh.points.size(), leafSize);
#else
  throw Error("this uvr was built without CUDA: use --backend cpu");
#endif
}

} // namespace uvr
