// The formulas that turn a predicted disparity into odometry quantities (DVSO,
// paper section 4). One implementation each, used by the odometry, the
// ablation tools and the tests.
//
// Units. A network trained on images of width W_t taken by a camera with focal
// length f_t and stereo baseline b_t learns the disparity as a FRACTION of the
// image width, delta = f_t b_t / (W_t Z) (monodepth convention; `dvso export`
// multiplies by the input width to output pixels). Shown an image of another
// camera (f_x, W), it still answers with the fraction it would have seen for
// the training camera, so in this image's pixels D = delta W and
//
//     Z = (f_t / W_t) b_t W / D,   d = 1 / Z = D / (f_x b_v),
//     b_v = b_t (f_t / W_t) / (f_x / W)                       (virtual baseline)
//
// i.e. the paper's d_p = D^L(p) / (f_x b) with the training baseline rescaled
// by the ratio of the two cameras' focal length per image width. For the
// training camera itself (or any camera with the same f_x / W, e.g. every
// KITTI sequence at full resolution) b_v = b_t. Images are resized to the
// network input, so the image height does not enter.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "core/camera.h"

namespace dvso {

// What a model file says about the images it was trained on (stored as JSON
// in the TorchScript file by `dvso export`, see docs/stacknet.md).
struct ModelMetadata {
  int input_width = 0;            // network input size (pixels)
  int input_height = 0;
  double baseline = 0;            // stereo baseline of the training images (metres)
  double fx_over_width = 0;       // focal length / image width of the training camera
  std::string config_name;        // training config the model came from
  std::string model_kind;         // "stack" or "simple"
  // Paper "tb": a virtual baseline found by `dvso tune-baseline` (grid search
  // on a sequence with ground truth, expressed for the training camera); 0 = none.
  double tuned_baseline = 0;
  std::string tuned_on;           // the sequence(s) it was tuned on

  bool has_camera() const { return baseline > 0 && fx_over_width > 0; }
  std::string ToJson() const;
  // Throws dvso::Error(source, ...) on malformed JSON or unknown keys.
  static ModelMetadata FromJson(const std::string& json, const std::string& source);
};

// Paper section 4: d_p = D(p) / (f_x b_v) (inverse depth in 1/m from a disparity
// in pixels of the image whose focal length is fx). Non-positive or non-finite
// disparities give 0 (no depth).
double InverseDepthFromDisparity(double disparity_px, double fx, double virtual_baseline);

// b_v for a camera with focal length fx and image width `width` (header
// comment), from the training baseline, or from the tuned one when `tuned`
// and the model carries one.
double VirtualBaselineForCamera(const ModelMetadata& model, double fx, int width, bool tuned = false);
// The inverse: a b_v found for that camera expressed for the training camera.
double TrainingCameraBaseline(const ModelMetadata& model, double virtual_baseline, double fx, int width);

// Paper section 4 (left-right check): e_lr = |D^L(p) - D^R(p')|, p' = p - (D^L(p), 0),
// D^R sampled bilinearly. Returns +infinity when D^L(p) or any D^R tap is
// invalid (<= 0, non-finite) or p' leaves the map.
float LeftRightDisparityError(const cv::Mat& disparity_left, const cv::Mat& disparity_right, int u, int v);

// Copy of a CV_32F disparity map with every non-finite or non-positive value
// set to 0 (invalid): NaN / negative network outputs never reach the odometry.
cv::Mat SanitizeDisparity(const cv::Mat& disparity);

}  // namespace dvso
