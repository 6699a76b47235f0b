// The residual pattern: every point contributes one residual per pattern
// pixel. DSO's 8-pixel pattern (a sparse diamond of radius 2), which DSO found
// the best trade-off between robustness to motion blur and speed.
#pragma once

#include <array>

namespace dvso::vo {

constexpr int kPatternSize = 8;

// (dx, dy) offsets in pixels around the point, level 0.
constexpr std::array<std::array<int, 2>, kPatternSize> kPatternOffsets = {{
    {{0, -2}}, {{-1, -1}}, {{1, -1}}, {{-2, 0}}, {{0, 0}}, {{2, 0}}, {{-1, 1}}, {{0, 2}},
}};

// Largest |offset| of the pattern: points must be this far plus the
// interpolation border inside the image.
constexpr int kPatternRadius = 2;

}  // namespace dvso::vo
