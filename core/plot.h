// Minimal 2-D line plots rendered with OpenCV into PNG files: axes with
// "nice" ticks (1, 2, 5 x 10^k), tick labels, axis labels, title and a legend.
// Enough for evaluation figures without a plotting dependency.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dvso {

struct PlotSeries {
  std::vector<double> x;                  // data x values (same length as y)
  std::vector<double> y;                  // data y values; non-finite values break the line
  cv::Scalar color = cv::Scalar(200, 0, 0);  // BGR
  std::string label;                      // legend entry; empty = not in the legend
  int thickness = 2;                      // line thickness in pixels (0 = no line)
  bool markers = false;                   // draw a small circle at every point
};

struct PlotOptions {
  int width = 900;             // image width, pixels
  int height = 700;            // image height, pixels
  std::string title;           // drawn above the axes
  std::string x_label;         // below the x axis
  std::string y_label;         // left of the y axis (drawn horizontally above it)
  bool equal_aspect = false;   // same data units per pixel on both axes (top-view trajectories)
  bool include_zero_y = false; // extend the y range to contain 0 (error plots)

  void Check() const;
};

// Ticks at multiples of 1, 2 or 5 x 10^k covering [lo, hi], about target_count of them.
std::vector<double> NiceTicks(double lo, double hi, int target_count);

// Renders the plot to a CV_8UC3 image. Throws dvso::Error when no series
// holds a finite point or a series has x/y of different lengths.
cv::Mat RenderPlot(const std::vector<PlotSeries>& series, const PlotOptions& options);

// Renders and writes a PNG atomically.
void WritePlotPng(const std::string& path, const std::vector<PlotSeries>& series, const PlotOptions& options);

}  // namespace dvso
