// SelectDevice: the thread budget reaches both LibTorch and OpenBLAS, whose own
// spinning pool otherwise competes with the odometry (stacknet/device.cpp).
#include <dlfcn.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "stacknet/device.h"

namespace dvso::stacknet {
namespace {

TEST(Device, ThreadBudgetReachesLibTorchAndOpenBlas) {
  using GetThreadsFn = int (*)();
  const auto blas_threads = reinterpret_cast<GetThreadsFn>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  if (blas_threads == nullptr) GTEST_SKIP() << "this LibTorch build does not load OpenBLAS";
  for (const int threads : {1, 2, 1}) {
    EXPECT_EQ(SelectDevice("cpu", threads), torch::Device(torch::kCPU));
    EXPECT_EQ(at::get_num_threads(), threads);
    EXPECT_EQ(blas_threads(), threads);
  }
}

TEST(Device, UnknownNameIsAOneLineError) {
  EXPECT_THROW(SelectDevice("tpu", 1), Error);
}

}  // namespace
}  // namespace dvso::stacknet
