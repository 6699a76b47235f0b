#include "core/camera.h"

#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "core/error.h"

namespace dvso {

void PinholeCamera::Check() const {
  Require(std::isfinite(fx) && fx > 0, "camera fx must be positive and finite");
  Require(std::isfinite(fy) && fy > 0, "camera fy must be positive and finite");
  Require(std::isfinite(cx) && std::isfinite(cy), "camera principal point must be finite");
  Require(width > 0 && height > 0, "camera image size must be positive");
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

PinholeCamera PinholeCamera::Resized(int new_width, int new_height) const {
  Require(new_width > 0 && new_height > 0, "resize target must be positive");
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  PinholeCamera out = *this;
  out.fx = fx * sx;
  out.fy = fy * sy;
  out.cx = (cx + 0.5) * sx - 0.5;
  out.cy = (cy + 0.5) * sy - 0.5;
  out.width = new_width;
  out.height = new_height;
  return out;
}

PinholeCamera PinholeCamera::Cropped(int x0, int y0, int w, int h) const {
  Require(x0 >= 0 && y0 >= 0 && w > 0 && h > 0 && x0 + w <= width && y0 + h <= height,
          "crop window outside the image");
  PinholeCamera out = *this;
  out.cx = cx - x0;
  out.cy = cy - y0;
  out.width = w;
  out.height = h;
  return out;
}

void StereoCamera::Check() const {
  left.Check();
  Require(std::isfinite(baseline) && baseline > 0, "stereo baseline must be positive and finite");
}

StereoCamera StereoCamera::Resized(int new_width, int new_height) const {
  return {left.Resized(new_width, new_height), baseline};
}

StereoCamera StereoCamera::Cropped(int x0, int y0, int w, int h) const {
  return {left.Cropped(x0, y0, w, h), baseline};
}

namespace {

std::vector<std::string> Tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

double ParseNumber(const std::string& path, const std::string& token) {
  try {
    size_t used = 0;
    const double v = std::stod(token, &used);
    if (used != token.size() || !std::isfinite(v)) throw std::invalid_argument(token);
    return v;
  } catch (const std::exception&) {
    throw Error(path, "expected a number, got '" + token + "'");
  }
}

}  // namespace

PinholeCamera ReadDsoCameraFile(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open camera file");
  std::string line1, line2;
  RequireFile(static_cast<bool>(std::getline(in, line1)), path, "empty camera file");
  RequireFile(static_cast<bool>(std::getline(in, line2)), path, "missing image size line");
  auto t1 = Tokens(line1);
  if (!t1.empty() && t1[0] == "Pinhole") t1.erase(t1.begin());
  RequireFile(!t1.empty(), path, "missing intrinsics");
  const bool is_number = std::isdigit(static_cast<unsigned char>(t1[0][0])) || t1[0][0] == '-' ||
                         t1[0][0] == '.';
  RequireFile(is_number, path, "camera model '" + t1[0] + "' is not supported (pinhole only)");
  RequireFile(t1.size() == 4 || t1.size() == 5, path, "intrinsics line needs fx fy cx cy [0]");
  if (t1.size() == 5) {
    RequireFile(ParseNumber(path, t1[4]) == 0.0, path,
                "distortion parameter must be 0 (rectify the images first)");
  }
  const auto t2 = Tokens(line2);
  RequireFile(t2.size() == 2, path, "image size line needs 'width height'");
  PinholeCamera cam;
  cam.width = static_cast<int>(ParseNumber(path, t2[0]));
  cam.height = static_cast<int>(ParseNumber(path, t2[1]));
  cam.fx = ParseNumber(path, t1[0]);
  cam.fy = ParseNumber(path, t1[1]);
  cam.cx = ParseNumber(path, t1[2]);
  cam.cy = ParseNumber(path, t1[3]);
  // DSO's convention: intrinsics below 1 are relative to the image size.
  if (cam.cx < 1 && cam.cy < 1) {
    cam.fx *= cam.width;
    cam.fy *= cam.height;
    cam.cx = cam.cx * cam.width - 0.5;
    cam.cy = cam.cy * cam.height - 0.5;
  }
  try {
    cam.Check();
  } catch (const Error& e) {
    throw Error(path, e.what());
  }
  // Lines 3-4 describe DSO's output image: "crop" / "full" / "none" or explicit intrinsics, then its size.
  // Without distortion DSO would only resample the images to that output; tracking the input images with
  // the intrinsics of line 1 gives the same poses, so an output that differs is not an error but is said
  // (the run's images keep their size). Lines that are not DSO's format are errors.
  std::string line3, line4;
  if (std::getline(in, line3) && !Tokens(line3).empty()) {
    const auto t3 = Tokens(line3);
    const bool named_mode = t3.size() == 1 && (t3[0] == "crop" || t3[0] == "full" || t3[0] == "none");
    RequireFile(named_mode || t3.size() == 4 || t3.size() == 5, path,
                "line 3 must be crop, full, none or 'fx fy cx cy 0', not '" + line3 + "'");
    RequireFile(static_cast<bool>(std::getline(in, line4)), path, "line 3 names an output but line 4 (its size) is missing");
    const auto t4 = Tokens(line4);
    RequireFile(t4.size() == 2, path, "output size line needs 'width height'");
    const int out_width = static_cast<int>(ParseNumber(path, t4[0]));
    const int out_height = static_cast<int>(ParseNumber(path, t4[1]));
    bool same_output = out_width == cam.width && out_height == cam.height;
    if (!named_mode) {
      RequireFile(t3.size() == 4 || ParseNumber(path, t3[4]) == 0.0, path, "output distortion must be 0");
      double out_k[4];
      for (int i = 0; i < 4; ++i) out_k[i] = ParseNumber(path, t3[i]);
      if (out_k[2] < 1 && out_k[3] < 1) {  // relative, as on line 1 (of the output size)
        out_k[0] *= out_width;
        out_k[1] *= out_height;
        out_k[2] = out_k[2] * out_width - 0.5;
        out_k[3] = out_k[3] * out_height - 0.5;
      }
      const double in_k[4] = {cam.fx, cam.fy, cam.cx, cam.cy};
      constexpr double kSameIntrinsicsPx = 0.5;  // relative values printed with 4-5 decimals differ by ~0.05 px
      for (int i = 0; i < 4; ++i) same_output = same_output && std::abs(out_k[i] - in_k[i]) <= kSameIntrinsicsPx;
    }
    if (!same_output) {
      std::cerr << "dvso: warning: " << path << ": DSO's output (lines 3-4: " << line3 << ", " << t4[0] << "x"
                << t4[1] << ") is not resampled to: the images are tracked at their own size with the intrinsics "
                   "of line 1 (the same poses)\n";
    }
  }
  return cam;
}

void WriteDsoCameraFile(const std::string& path, const PinholeCamera& camera) {
  std::ofstream out(path);
  RequireFile(out.good(), path, "cannot write camera file");
  out.precision(10);
  out << "Pinhole " << camera.fx << " " << camera.fy << " " << camera.cx << " " << camera.cy
      << " 0\n"
      << camera.width << " " << camera.height << "\nnone\n"
      << camera.width << " " << camera.height << "\n";
}

}  // namespace dvso
