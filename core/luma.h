// The grey value of an RGB colour: ITU-R BT.601 luma weights, the ones OpenCV's cv::COLOR_BGR2GRAY applies.
// One definition for everything that turns colour into grey: the simulator renders its grey cameras with it
// (core/simulator_render.cpp) and the training's grey augmentation (stacknet/augmentation.h) makes grey
// inputs like those, so a network trained on colour also sees the grey images DVSO feeds it from a KITTI
// image_0 sequence.
#pragma once

namespace dvso {

inline constexpr float kLumaWeightRed = 0.299f;
inline constexpr float kLumaWeightGreen = 0.587f;
inline constexpr float kLumaWeightBlue = 0.114f;

inline float Luma(float red, float green, float blue) {
  return kLumaWeightRed * red + kLumaWeightGreen * green + kLumaWeightBlue * blue;
}

}  // namespace dvso
