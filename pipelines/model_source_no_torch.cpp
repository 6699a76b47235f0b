// OpenModelDisparitySource for builds without LibTorch (DVSO_WITH_TORCH=OFF).
#ifndef DVSO_WITH_TORCH
#include "core/error.h"
#include "pipelines/prediction_source.h"

namespace dvso::cli {

std::unique_ptr<DisparitySource> OpenModelDisparitySource(const std::string& path, int, ModelMetadata*) {
  throw Error(path, "this build has no LibTorch: use --disparity-left/--disparity-right or rebuild with "
                    "-DDVSO_WITH_TORCH=ON");
}

void WriteModelWithTunedBaseline(const std::string& in_path, const std::string&, const ModelMetadata&) {
  throw Error(in_path, "this build has no LibTorch: cannot write models");
}

}  // namespace dvso::cli
#endif
