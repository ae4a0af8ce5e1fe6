/* gpu_ceilings.cu — the two ceilings the GPU benchmark is compared with
 * (tools/bench/bench_gpu.sh; docs/gpu.md), measured on the device as found:
 *   memory bandwidth: a 4 GiB device-to-device cudaMemcpy, bytes read plus
 *                     bytes written over the time (median of 10);
 *   FP64 and FP32 rates: cuBLAS DGEMM and SGEMM, n = 8192, 2 n^3 flops over
 *                     the time (median of 5; default math mode, so DGEMM may
 *                     use the FP64 tensor cores and SGEMM plain FP32).
 * Inputs are random (never zeros). Build and run:
 *   nvcc -O3 -arch=sm_90 tools/bench/gpu_ceilings.cu -lcublas -o /tmp/ceil && /tmp/ceil */
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <cublas_v2.h>
#include <cuda_runtime.h>
#include "bench_cuda.h"

__global__ void fill(double *a, size_t n, unsigned seed)
{
    size_t i = blockIdx.x * (size_t)blockDim.x + threadIdx.x;
    if (i < n) a[i] = ((i * 2654435761u + seed) % 1000003) / 1000003.0 + 0.5;
}
__global__ void fillf(float *a, size_t n, unsigned seed)
{
    size_t i = blockIdx.x * (size_t)blockDim.x + threadIdx.x;
    if (i < n) a[i] = ((i * 2654435761u + seed) % 1000003) / 1000003.0f + 0.5f;
}

int main()
{
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, 0));
    cudaEvent_t a, b;
    CK(cudaEventCreate(&a));
    CK(cudaEventCreate(&b));
    size_t bytes = (size_t)4 << 30, n = bytes / 8;
    double *x, *y;
    CK(cudaMalloc(&x, bytes));
    CK(cudaMalloc(&y, bytes));
    fill<<<(n + 255) / 256, 256>>>(x, n, 1);
    CK(cudaMemcpy(y, x, bytes, cudaMemcpyDeviceToDevice));
    std::vector<double> t;
    for (int r = 0; r < 10; ++r) {
        CK(cudaEventRecord(a));
        CK(cudaMemcpy(r % 2 ? x : y, r % 2 ? y : x, bytes, cudaMemcpyDeviceToDevice));
        CK(cudaEventRecord(b));
        CK(cudaEventSynchronize(b));
        float ms;
        CK(cudaEventElapsedTime(&ms, a, b));
        t.push_back(ms * 1e-3);
    }
    double bw = 2.0 * bytes / median(t);
    CK(cudaFree(x));
    CK(cudaFree(y));

    cublasHandle_t h;
    if (cublasCreate(&h) != CUBLAS_STATUS_SUCCESS) return fprintf(stderr, "cublasCreate failed\n"), 1;
    const int m = 8192;
    double rate[2];
    for (int prec = 0; prec < 2; ++prec) {
        size_t es = prec ? sizeof(float) : sizeof(double), nn = (size_t)m * m;
        void *A, *B, *C;
        CK(cudaMalloc(&A, nn * es));
        CK(cudaMalloc(&B, nn * es));
        CK(cudaMalloc(&C, nn * es));
        if (prec) {
            fillf<<<(nn + 255) / 256, 256>>>((float *)A, nn, 2);
            fillf<<<(nn + 255) / 256, 256>>>((float *)B, nn, 3);
        } else {
            fill<<<(nn + 255) / 256, 256>>>((double *)A, nn, 2);
            fill<<<(nn + 255) / 256, 256>>>((double *)B, nn, 3);
        }
        std::vector<double> tt;
        for (int r = 0; r < 6; ++r) {
            double one = 1, zero = 0;
            float onef = 1, zerof = 0;
            CK(cudaEventRecord(a));
            cublasStatus_t st = prec ? cublasSgemm(h, CUBLAS_OP_N, CUBLAS_OP_N, m, m, m, &onef, (float *)A, m,
                                                   (float *)B, m, &zerof, (float *)C, m)
                                     : cublasDgemm(h, CUBLAS_OP_N, CUBLAS_OP_N, m, m, m, &one, (double *)A, m,
                                                   (double *)B, m, &zero, (double *)C, m);
            CK(cudaEventRecord(b));
            CK(cudaEventSynchronize(b));
            if (st != CUBLAS_STATUS_SUCCESS) return fprintf(stderr, "gemm failed\n"), 1;
            float ms;
            CK(cudaEventElapsedTime(&ms, a, b));
            if (r) tt.push_back(ms * 1e-3); /* the first is warm-up */
        }
        rate[prec] = 2.0 * m * (double)m * m / median(tt);
        CK(cudaFree(A));
        CK(cudaFree(B));
        CK(cudaFree(C));
    }
    printf("device,memory_bandwidth_GBps,dgemm_TFLOPS,sgemm_TFLOPS\n");
    printf("%s,%.0f,%.1f,%.1f\n", prop.name, bw * 1e-9, rate[0] * 1e-12, rate[1] * 1e-12);
    return 0;
}
