// DSO's 8-pixel residual pattern (a sparse diamond of radius 2 around the
// point): each point contributes one photometric residual per pattern pixel.
// The pattern is shared by tracking, immature-point tracing and the windowed
// optimisation so that every stage compares the same pixels.
#pragma once

namespace dvso::vo {

constexpr int kPatternSize = 8;
constexpr int kPatternPadding = 2;  // max |offset|: keep points this far (+1) from the border
constexpr int kPattern[kPatternSize][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0},
                                           {0, 0},  {2, 0},   {-1, 1}, {0, 2}};

}  // namespace dvso::vo
