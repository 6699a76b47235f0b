#include "stacknet/device.h"

#include <dlfcn.h>

#include <thread>

#include "core/error.h"

namespace dvso::stacknet {
namespace {

// LibTorch's CPU kernels call BLAS, and Debian's OpenBLAS (pthread flavour) keeps its
// own pool of one thread per core that busy-waits (sched_yield) between calls. Beside
// at::set_num_threads(1) that pool still spins on the other core: measured on 2 cores,
// `dvso bench --threads 1` spent 100 ms of system time per 110 ms inference, and in DVSO
// mode the spinning competed with tracking. The BLAS pool therefore gets the same thread
// budget as LibTorch. Looked up at run time: other BLAS builds have no such symbol.
void SetBlasThreads(int threads) {
  using SetThreadsFn = void (*)(int);
  if (auto set = reinterpret_cast<SetThreadsFn>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(threads);
}

}  // namespace

torch::Device SelectDevice(const std::string& name, int num_threads) {
  Require(name == "auto" || name == "cpu" || name == "cuda", "device must be auto, cpu or cuda, got '" + name + "'");
  const bool cuda = torch::cuda::is_available();
  Require(name != "cuda" || cuda, "device 'cuda' requested but this LibTorch build sees no CUDA device");
  const int threads = num_threads > 0 ? num_threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  at::set_num_threads(threads);
  SetBlasThreads(threads);
  if (name == "cuda" || (name == "auto" && cuda)) return torch::Device(torch::kCUDA);
  return torch::Device(torch::kCPU);
}

torch::Tensor ToConvolutionLayout(const torch::Tensor& input, const torch::Device& device) {
  return device.is_cpu() && input.dim() == 4 ? input.contiguous(at::MemoryFormat::ChannelsLast) : input.contiguous();
}

}  // namespace dvso::stacknet
