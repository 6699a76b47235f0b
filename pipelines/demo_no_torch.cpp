// RunDemoDepthNetwork for builds without LibTorch (DVSO_WITH_TORCH=OFF).
#ifndef DVSO_WITH_TORCH
#include <iostream>

#include "pipelines/demo_steps.h"

namespace dvso::cli {

nlohmann::json RunDemoDepthNetwork(const std::string&, const std::string&, const std::string&, bool) {
  std::cout << "skipped: this build has no LibTorch (configure with -DDVSO_WITH_TORCH=ON)\n";
  return {{"skipped", "built without LibTorch"}};
}

}  // namespace dvso::cli
#endif
