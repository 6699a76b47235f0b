// Device choice: CUDA when present (or asked for), else CPU with the intra-op
// thread count set to the hardware cores.
#pragma once

#include <torch/torch.h>

#include <string>

namespace dvso::stacknet {

// name: "auto" | "cpu" | "cuda". num_threads: 0 = hardware cores. Throws
// dvso::Error when CUDA is requested but unavailable.
torch::Device SelectDevice(const std::string& name, int num_threads = 0);

}  // namespace dvso::stacknet
