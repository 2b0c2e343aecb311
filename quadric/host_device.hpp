// Marks functions that are compiled for both the CPU and the GPU. The quadric residuals and
// Jacobians are written once with JPCR_HD so the CPU reference and the CUDA kernels share them.
#pragma once

#if defined(__CUDACC__)
#define JPCR_HD __host__ __device__ __forceinline__
#else
#define JPCR_HD inline
#endif
