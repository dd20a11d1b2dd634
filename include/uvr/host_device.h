// Marks the functions of the public value types that CUDA device code may call too.
#pragma once

#if defined(__CUDACC__)
#define UVR_HOST_DEVICE __host__ __device__
#else
#define UVR_HOST_DEVICE
#endif
