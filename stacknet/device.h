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

// The layout the network's input is given in, for training and inference alike: channels-last (NHWC) for a
// 4-D tensor bound for the CPU (no copy when it has that layout already, e.g. an NHWC image viewed as NCHW),
// contiguous NCHW for other devices. LibTorch 1.13's oneDNN convolutions keep the layout of their input, and
// in NHWC they skip reordering every activation on each call; the numbers are the same. Measured with
// benchmarks/bench_torch_train_step (docs/stacknet.md): the backward pass of the decoder's full-resolution
// convolutions (2-8 channels) takes several times longer in NCHW.
torch::Tensor ToConvolutionLayout(const torch::Tensor& input, const torch::Device& device);

}  // namespace dvso::stacknet
