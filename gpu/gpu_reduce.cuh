/* gpu/gpu_reduce.cuh — reduce (a CUB device reduction in the CUB scratch), and
 * the thrust iterators the reductions read through; their functors are in
 * gpu_launch.cuh. Included by the units that reduce only: parsing CUB costs
 * a unit about 6 s of compile time. */
#ifndef SPHSEG_GPU_REDUCE_CUH
#define SPHSEG_GPU_REDUCE_CUH

#include <cub/device/device_reduce.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
#include "gpu.cuh"

template <class It, class T, class Op> static void reduce(gpu_t *g, It in, T *out, size_t n, Op op, T init)
{
    size_t bytes = 0;
    CK(cub::DeviceReduce::Reduce(NULL, bytes, in, out, (int64_t)n, op, init, g->st));
    CK(cub::DeviceReduce::Reduce(scratch(g, bytes), bytes, in, out, (int64_t)n, op, init, g->st));
}

#endif
