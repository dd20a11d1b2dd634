// Marks functions that the CPU backend and the CUDA backend both compile.
#pragma once

#include <uvr/host_device.h>

// Inlined into each caller even where the compiler would rather call it: for the host's hot loops, where a
// call leaves the caller's state in memory rather than registers. A GPU compiler inlines on its own.
#if defined(__CUDA_ARCH__)
#define UVR_HOST_INLINE inline
#else
#define UVR_HOST_INLINE inline __attribute__((always_inline))
#endif

// Called, not inlined, on the GPU: one copy of a large function that several call sites share, where a copy
// at each would crowd the kernel's hot code out of the instruction cache. The host inlines as it sees fit.
#if defined(__CUDA_ARCH__)
#define UVR_DEVICE_NOINLINE __noinline__
#else
#define UVR_DEVICE_NOINLINE inline
#endif
