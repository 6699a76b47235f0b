// Device choice: CUDA when present (or asked for), else CPU with the intra-op
// thread count (LibTorch and OpenBLAS) set to the hardware cores.
#pragma once

#include <torch/torch.h>

#include <string>

namespace dvso::stacknet {

// name: "auto" | "cpu" | "cuda". num_threads: 0 = hardware cores; it is also the
// OpenBLAS pool size when that library is loaded. Throws
// dvso::Error when CUDA is requested but unavailable.
torch::Device SelectDevice(const std::string& name, int num_threads = 0);

}  // namespace dvso::stacknet
