// Fused element-wise kernels of the CuPy backend (granframe_cupy.CuPyBackend).
//
// They implement ArrayBackend.separable_product and ArrayBackend.lowrank_accumulate
// (granframe/backends.py, where the formulas are stated) in one pass over memory each,
// where the generic xp code makes several passes and temporaries. Every output element is
// written by exactly one thread of a grid-stride loop, so any launch shape gives the same
// result. All arrays are C-contiguous and of one complex type T (complex<float> or
// complex<double>).
//
// The same source is compiled for the host by tests/test_cupy_kernels.py with a one-thread
// launch shim (GRANFRAME_HOST_SHIM), so the index arithmetic is checked without a GPU.

#ifndef GRANFRAME_HOST_SHIM
#include <cupy/complex.cuh>
#endif

// out[d, b, i, j] = spectrum[d, i, j] * head[b, i] * tail[b, j]; out (D, B, I, J), spectrum
// (D, I, J), head (B, I), tail (B, J). D = distributions, 1 by default (out (B, I, J),
// spectrum (I, J)).
template <typename T>
__global__ void separable_product(T* __restrict__ out, const T* __restrict__ spectrum,
                                  const T* __restrict__ head, const T* __restrict__ tail,
                                  long long batch, long long rows, long long cols,
                                  long long distributions = 1)
{
    const long long plane = rows * cols;
    const long long stack = batch * plane;
    const long long size = distributions * stack;
    const long long stride = (long long)blockDim.x * gridDim.x;
    for (long long k = (long long)blockIdx.x * blockDim.x + threadIdx.x; k < size; k += stride) {
        const long long d = k / stack;
        const long long bij = k - d * stack;
        const long long b = bij / plane;
        const long long ij = bij - b * plane;
        const long long i = ij / cols;
        const long long j = ij - i * cols;
        out[k] = spectrum[d * plane + ij] * (head[b * rows + i] * tail[b * cols + j]);
    }
}

// acc[d, q, i, j] += sum over b in group q of (sum_t heads[b, i, t] tails[b, t, j])
// values[d, b, i, j]; acc (D, Q, I, J), heads (B, I, R), tails (B, R, J), values
// (D, B, I, J); group q holds the consecutive entries b = q B/Q, ..., (q + 1) B/Q - 1.
// D = distributions, 1 by default (acc (Q, I, J), values (B, I, J)).
template <typename T>
__global__ void lowrank_accumulate(T* __restrict__ acc, const T* __restrict__ heads,
                                   const T* __restrict__ tails, const T* __restrict__ values,
                                   long long groups, long long per_group, long long rows,
                                   long long cols, long long rank,
                                   long long distributions = 1)
{
    const long long plane = rows * cols;
    const long long batch = groups * per_group;
    const long long size = distributions * groups * plane;
    const long long stride = (long long)blockDim.x * gridDim.x;
    for (long long k = (long long)blockIdx.x * blockDim.x + threadIdx.x; k < size; k += stride) {
        const long long dq = k / plane;
        const long long d = dq / groups;
        const long long q = dq - d * groups;
        const long long ij = k - dq * plane;
        const long long i = ij / cols;
        const long long j = ij - i * cols;
        T sum = acc[k];
        for (long long b = q * per_group; b < (q + 1) * per_group; ++b) {
            T weight = T(0);
            for (long long t = 0; t < rank; ++t) {
                weight += heads[(b * rows + i) * rank + t] * tails[(b * rank + t) * cols + j];
            }
            sum += weight * values[(d * batch + b) * plane + ij];
        }
        acc[k] = sum;
    }
}
