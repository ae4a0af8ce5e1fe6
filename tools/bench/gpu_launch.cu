/* gpu_launch.cu — the launch floor of a small step (issue 56: the 2D drums
 * at 10^4 particles run at a few microseconds of work a kernel), measured on
 * the device as found. A "step" is K dependent kernels over n elements (each
 * a short chain of arithmetic on one array, a few microseconds at n = 10^4),
 * a 4-byte read-back and a stream synchronisation, as sphseg's step ends with
 * its check. Three ways of issuing it, the median of 5 repeats of S steps:
 *   direct:  K launches on a stream, the copy, the synchronisation;
 *   replay:  the K kernels and the copy captured once in a CUDA graph,
 *            replayed (cudaGraphLaunch) and synchronised each step;
 *   update:  captured again every step (the host's launch code runs, into
 *            the graph) and cudaGraphExecUpdate into the one instantiated
 *            graph, then replayed: what a step whose kernel arguments
 *            change from step to step would pay;
 * and "sync" alone: an empty stream's synchronisation after a 4-byte copy.
 * Output: CSV, one row a (K, n), microseconds a step.
 *   nvcc -O3 -arch=sm_90 tools/bench/gpu_launch.cu -o /tmp/launch && /tmp/launch [K ...] */
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <cuda_runtime.h>
#include "bench_cuda.h"

__global__ void work(double *a, size_t n, double s)
{
    size_t i = blockIdx.x * (size_t)blockDim.x + threadIdx.x;
    if (i >= n) return;
    double x = a[i];
    for (int k = 0; k < 32; ++k) x = x * 0.999999 + s;
    a[i] = x;
}

static double now()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

static void issue(cudaStream_t st, double *a, size_t n, int K, int step, float *d, float *h)
{
    for (int k = 0; k < K; ++k) work<<<(unsigned)((n + 127) / 128), 128, 0, st>>>(a, n, 1e-9 * (step + k));
    CK(cudaMemcpyAsync(h, d, sizeof *d, cudaMemcpyDeviceToHost, st));
}

int main(int argc, char **argv)
{
    std::vector<int> Ks;
    for (int i = 1; i < argc; ++i) Ks.push_back(atoi(argv[i]));
    if (Ks.empty()) Ks = {1, 6, 12, 24};
    const size_t ns[] = {10000, 100000};
    const int S = 2000, R = 5;
    cudaStream_t st;
    CK(cudaStreamCreateWithFlags(&st, cudaStreamNonBlocking));
    double *a;
    float *d, *h;
    CK(cudaMalloc(&a, 100000 * sizeof *a));
    CK(cudaMemset(a, 0, 100000 * sizeof *a));
    CK(cudaMalloc(&d, sizeof *d));
    CK(cudaMallocHost(&h, sizeof *h));
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, 0));
    printf("device,K,n,direct_us,replay_us,update_us,sync_us,kernels_alone_us\n");
    for (size_t n : ns)
        for (int K : Ks) {
            std::vector<double> td, tr, tu, ts, tk;
            cudaGraph_t gr;
            cudaGraphExec_t ex;
            CK(cudaStreamBeginCapture(st, cudaStreamCaptureModeThreadLocal));
            issue(st, a, n, K, 0, d, h);
            CK(cudaStreamEndCapture(st, &gr));
            CK(cudaGraphInstantiate(&ex, gr, 0));
            cudaEvent_t e0, e1;
            CK(cudaEventCreate(&e0));
            CK(cudaEventCreate(&e1));
            for (int r = 0; r < R + 1; ++r) { /* the first repeat warms up */
                double t0 = now();
                for (int s = 0; s < S; ++s) {
                    issue(st, a, n, K, s, d, h);
                    CK(cudaStreamSynchronize(st));
                }
                double t1 = now();
                for (int s = 0; s < S; ++s) {
                    CK(cudaGraphLaunch(ex, st));
                    CK(cudaStreamSynchronize(st));
                }
                double t2 = now();
                for (int s = 0; s < S; ++s) {
                    cudaGraph_t g2;
                    CK(cudaStreamBeginCapture(st, cudaStreamCaptureModeThreadLocal));
                    issue(st, a, n, K, s, d, h);
                    CK(cudaStreamEndCapture(st, &g2));
                    cudaGraphExecUpdateResultInfo info;
                    CK(cudaGraphExecUpdate(ex, g2, &info));
                    CK(cudaGraphDestroy(g2));
                    CK(cudaGraphLaunch(ex, st));
                    CK(cudaStreamSynchronize(st));
                }
                double t3 = now();
                for (int s = 0; s < S; ++s) {
                    CK(cudaMemcpyAsync(h, d, sizeof *d, cudaMemcpyDeviceToHost, st));
                    CK(cudaStreamSynchronize(st));
                }
                double t4 = now();
                /* the kernels' own time: S steps queued without synchronising, between events */
                CK(cudaEventRecord(e0, st));
                for (int s = 0; s < S; ++s) CK(cudaGraphLaunch(ex, st));
                CK(cudaEventRecord(e1, st));
                CK(cudaEventSynchronize(e1));
                float ms;
                CK(cudaEventElapsedTime(&ms, e0, e1));
                if (r == 0) continue;
                td.push_back((t1 - t0) / S), tr.push_back((t2 - t1) / S), tu.push_back((t3 - t2) / S);
                ts.push_back((t4 - t3) / S), tk.push_back(1e-3 * ms / S);
            }
            printf("%s,%d,%zu,%.2f,%.2f,%.2f,%.2f,%.2f\n", prop.name, K, n, 1e6 * median(td), 1e6 * median(tr),
                   1e6 * median(tu), 1e6 * median(ts), 1e6 * median(tk));
            fflush(stdout);
            CK(cudaGraphExecDestroy(ex));
            CK(cudaGraphDestroy(gr));
        }
    return 0;
}
