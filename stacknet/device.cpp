#include "stacknet/device.h"

#include <thread>

#include "core/error.h"

namespace dvso::stacknet {

torch::Device SelectDevice(const std::string& name, int num_threads) {
  Require(name == "auto" || name == "cpu" || name == "cuda", "device must be auto, cpu or cuda, got '" + name + "'");
  const bool cuda = torch::cuda::is_available();
  Require(name != "cuda" || cuda, "device 'cuda' requested but this LibTorch build sees no CUDA device");
  const int threads = num_threads > 0 ? num_threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  at::set_num_threads(threads);
  if (name == "cuda" || (name == "auto" && cuda)) return torch::Device(torch::kCUDA);
  return torch::Device(torch::kCPU);
}

}  // namespace dvso::stacknet
