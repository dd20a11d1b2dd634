// Marks functions that the CPU backend and the CUDA backend both compile.
#pragma once

#if defined(__CUDACC__)
#define UVR_HOST_DEVICE __host__ __device__
#define UVR_INLINE __forceinline__
#else
#define UVR_HOST_DEVICE
#define UVR_INLINE inline
#endif
