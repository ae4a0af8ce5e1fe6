/* bench_cuda.h — what the standalone CUDA benchmarks of tools/bench share
 * (gpu_ceilings.cu, gpu_launch.cu): a CUDA call checked (exit 1 with the
 * error), and the median of repeats. */
#ifndef SPHSEG_BENCH_CUDA_H
#define SPHSEG_BENCH_CUDA_H
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <cuda_runtime.h>

#define CK(x)                                                                        \
    do {                                                                             \
        cudaError_t e_ = (x);                                                        \
        if (e_ != cudaSuccess) {                                                     \
            fprintf(stderr, "%s:%d %s\n", __FILE__, __LINE__, cudaGetErrorString(e_)); \
            exit(1);                                                                 \
        }                                                                            \
    } while (0)

static inline double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

#endif
