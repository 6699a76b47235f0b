// The formulas that turn a predicted disparity into odometry quantities (DVSO,
// paper section 4). One implementation each, used by the odometry, the
// ablation tools and the tests.
//
// Units. A network trained on images of width W_t taken by a camera with focal
// length f_t and stereo baseline b_t learns the disparity as a FRACTION of the
// image width, delta = f_t b_t / (W_t Z) (monodepth convention; `dvso export`
// multiplies by the input width to output pixels, and the image's own width
// turns it into pixels of the image: D = delta W).
//
// Virtual baseline: b_v = b_t (or the tuned one) whatever the camera's focal
// length, and d = 1 / Z = D / (f_x b_v). Why not rescaled by the cameras' focal
// length per width: the network reads depth from image cues measured in
// fractions of the image (the apparent size s f / (W Z) of an object of size s,
// the height h f_y / (H Z) of its ground contact below the horizon), so shown a
// camera with another focal length it perceives Z' = Z (f_t / W_t) / (f_x / W)
// (the focal-length ambiguity of monocular depth) and answers
// delta = (f_t / W_t) b_t / Z' = (f_x / W) b_t / Z, i.e. D = f_x b_t / Z in the
// image's pixels: the camera's focal length is in the prediction already.
// This holds when the horizontal and vertical cues agree, i.e. the image has the
// training images' shape (f_x / W : f_y / H as for the training camera; every
// KITTI-like camera). An image of another aspect ratio is squeezed into the
// network's input, the two kinds of cue then imply different depths, and no
// formula of the metadata gives the answer: `dvso tune-baseline` on a sequence
// with ground truth does. Measured (session 24, docs/dvso.md): simulated streets
// at 1241x376 seen with 1.5x and 0.7x KITTI's focal length (f_x = f_y), shipped
// model: Sim(3) scale 1.009 / 1.117 with b_v = b_t (0.54 m), 0.974 / 1.079 with
// its tuned 0.56 m; 1.51 at 1.5x with the b_v of the pre-session-24 rule
// b_v = b_t (f_t / W_t) / (f_x / W). The training camera's f_t / W_t stays in the
// metadata to describe the model.
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

// b_v of a model for any camera (header comment): the training baseline, or the
// tuned one when `tuned` and the model carries one.
double VirtualBaselineOfModel(const ModelMetadata& model, bool tuned = false);

// Paper section 4 (left-right check): e_lr = |D^L(p) - D^R(p')|, p' = p - (D^L(p), 0),
// D^R sampled bilinearly. Returns +infinity when D^L(p) or any D^R tap is
// invalid (<= 0, non-finite) or p' leaves the map.
float LeftRightDisparityError(const cv::Mat& disparity_left, const cv::Mat& disparity_right, int u, int v);

// Copy of a CV_32F disparity map with every non-finite or non-positive value
// set to 0 (invalid): NaN / negative network outputs never reach the odometry.
cv::Mat SanitizeDisparity(const cv::Mat& disparity);

}  // namespace dvso
