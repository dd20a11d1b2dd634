#include "backend/backend.h"

#include "backend/cpu/cpu_backend.h"
#include <uvr/error.h>
#ifdef UVR_HAVE_CUDA
#include "backend/cuda/cuda_backend.h"
#endif

namespace uvr {

std::unique_ptr<RenderBackend> makeBackend(Backend backend, const Mesh &mesh, const MeshView &view,
                                           uint32_t leafSize, MemoryLayout layout) {
  if (backend == Backend::Cpu)
    return std::make_unique<CpuBackend>(mesh, view, leafSize, layout);
#ifdef UVR_HAVE_CUDA
  return std::make_unique<CudaBackend>(mesh, view, leafSize, layout);
#else
  throw Error("this build of uvr has no CUDA backend (no CUDA toolkit was found at build time)");
#endif
}

} // namespace uvr
