#include "core/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"

namespace dvso {

void PlotOptions::Check() const {
  Require(width >= 200 && height >= 150, "plot size must be at least 200 x 150 pixels");
}

std::vector<double> NiceTicks(double lo, double hi, int target_count) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi <= lo || target_count < 1) return ticks;
  const double raw_step = (hi - lo) / target_count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw_step)));
  double step = magnitude;
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    step = factor * magnitude;
    if (step >= raw_step) break;
  }
  // Index-based so that a step below the resolution of lo cannot loop forever.
  const double first_index = std::ceil(lo / step - 1e-9);
  const double last_index = std::floor(hi / step + 1e-9);
  if (!(last_index - first_index < 1000.0)) return ticks;
  for (double k = first_index; k <= last_index; k += 1.0) ticks.push_back(k == 0.0 ? 0.0 : k * step);
  return ticks;
}

namespace {

const int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);

std::string TickLabel(double value, double step) {
  // Enough decimals to tell neighbouring ticks apart.
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", std::min(decimals, 6), value);
  return buf;
}

// align_x / align_y: the point of the text's box placed at anchor, 0 = left / top, 1 = right / bottom.
void DrawText(cv::Mat* image, const std::string& text, cv::Point anchor, double scale, int thickness,
              double align_x, double align_y) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  const cv::Point origin(anchor.x - static_cast<int>(align_x * size.width),
                         anchor.y + static_cast<int>((1.0 - align_y) * size.height));
  cv::putText(*image, text, origin, kFont, scale, kBlack, thickness, cv::LINE_AA);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  // Pads by a fraction and guarantees a non-empty interval.
  void Pad(double fraction) {
    double span = hi - lo;
    if (span <= 0.0) span = std::max(1.0, std::abs(lo)) * 0.1;
    const double centre = 0.5 * (lo + hi);
    lo = std::min(lo, centre - 0.5 * span) - fraction * span;
    hi = std::max(hi, centre + 0.5 * span) + fraction * span;
  }
};

}  // namespace

cv::Mat RenderPlot(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  options.Check();
  Range x_range, y_range;
  for (const PlotSeries& s : series) {
    Require(s.x.size() == s.y.size(), "plot series '" + s.label + "' has x and y of different lengths");
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_range.Add(s.x[i]);
      y_range.Add(s.y[i]);
    }
  }
  Require(x_range.lo <= x_range.hi, "plot '" + options.title + "' has no finite point to draw");
  if (options.include_zero_y) y_range.Add(0.0);
  x_range.Pad(0.04);
  y_range.Pad(0.06);

  cv::Mat image(options.height, options.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 90, right = 25, top = 60, bottom = 65;
  const cv::Rect area(left, top, options.width - left - right, options.height - top - bottom);
  if (options.equal_aspect) {
    // Widen the tighter axis so that one data unit spans the same pixels on both.
    const double units_per_px = std::max((x_range.hi - x_range.lo) / area.width,
                                         (y_range.hi - y_range.lo) / area.height);
    const double cx = 0.5 * (x_range.lo + x_range.hi), cy = 0.5 * (y_range.lo + y_range.hi);
    x_range.lo = cx - 0.5 * units_per_px * area.width;
    x_range.hi = cx + 0.5 * units_per_px * area.width;
    y_range.lo = cy - 0.5 * units_per_px * area.height;
    y_range.hi = cy + 0.5 * units_per_px * area.height;
  }
  auto to_px = [&](double x, double y) {
    const double u = area.x + (x - x_range.lo) / (x_range.hi - x_range.lo) * area.width;
    const double v = area.y + area.height - (y - y_range.lo) / (y_range.hi - y_range.lo) * area.height;
    return cv::Point2d(u, v);
  };

  // Grid, ticks and tick labels.
  const std::vector<double> x_ticks = NiceTicks(x_range.lo, x_range.hi, 8);
  const std::vector<double> y_ticks = NiceTicks(y_range.lo, y_range.hi, 8);
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  for (const double t : x_ticks) {
    const int u = static_cast<int>(std::lround(to_px(t, y_range.lo).x));
    cv::line(image, {u, area.y}, {u, area.y + area.height}, kGrid, 1);
    cv::line(image, {u, area.y + area.height}, {u, area.y + area.height + 6}, kBlack, 1);
    DrawText(&image, TickLabel(t, x_step), {u, area.y + area.height + 10}, 0.45, 1, 0.5, 0.0);
  }
  for (const double t : y_ticks) {
    const int v = static_cast<int>(std::lround(to_px(x_range.lo, t).y));
    cv::line(image, {area.x, v}, {area.x + area.width, v}, kGrid, 1);
    cv::line(image, {area.x - 6, v}, {area.x, v}, kBlack, 1);
    DrawText(&image, TickLabel(t, y_step), {area.x - 10, v}, 0.45, 1, 1.0, 0.5);
  }
  cv::rectangle(image, area, kBlack, 1);

  // Data, clipped to the axes area.
  cv::Mat canvas = image(area);
  const cv::Point2d offset(area.x, area.y);
  constexpr int kShift = 4;  // sub-pixel line drawing
  auto fixed = [&](const cv::Point2d& p) {
    return cv::Point(static_cast<int>(std::lround((p.x - offset.x) * (1 << kShift))),
                     static_cast<int>(std::lround((p.y - offset.y) * (1 << kShift))));
  };
  for (const PlotSeries& s : series) {
    bool has_previous = false;
    cv::Point previous;
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        has_previous = false;
        continue;
      }
      const cv::Point p = fixed(to_px(s.x[i], s.y[i]));
      if (has_previous && s.thickness > 0) cv::line(canvas, previous, p, s.color, s.thickness, cv::LINE_AA, kShift);
      if (s.markers) cv::circle(canvas, p, 4 << kShift, s.color, cv::FILLED, cv::LINE_AA, kShift);
      previous = p;
      has_previous = true;
    }
  }

  // Title and axis labels.
  DrawText(&image, options.title, {options.width / 2, 18}, 0.65, 2, 0.5, 0.0);
  DrawText(&image, options.x_label, {area.x + area.width / 2, options.height - 22}, 0.55, 1, 0.5, 0.0);
  DrawText(&image, options.y_label, {8, top - 22}, 0.55, 1, 0.0, 0.0);

  // Legend in the top-right corner of the axes.
  std::vector<const PlotSeries*> entries;
  int text_width = 0;
  for (const PlotSeries& s : series) {
    if (s.label.empty()) continue;
    entries.push_back(&s);
    int baseline = 0;
    text_width = std::max(text_width, cv::getTextSize(s.label, kFont, 0.5, 1, &baseline).width);
  }
  if (!entries.empty()) {
    const int row = 22, box_w = text_width + 50, box_h = row * static_cast<int>(entries.size()) + 8;
    const cv::Rect box(area.x + area.width - box_w - 8, area.y + 8, box_w, box_h);
    cv::rectangle(image, box, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(image, box, kBlack, 1);
    for (size_t k = 0; k < entries.size(); ++k) {
      const int v = box.y + 4 + row * static_cast<int>(k) + row / 2;
      const cv::Point a(box.x + 8, v), b(box.x + 36, v);
      if (entries[k]->thickness > 0) cv::line(image, a, b, entries[k]->color, entries[k]->thickness, cv::LINE_AA);
      if (entries[k]->markers) cv::circle(image, (a + b) / 2, 4, entries[k]->color, cv::FILLED, cv::LINE_AA);
      DrawText(&image, entries[k]->label, {box.x + 44, v}, 0.5, 1, 0.0, 0.5);
    }
  }
  return image;
}

void WritePlotPng(const std::string& path, const std::vector<PlotSeries>& series, const PlotOptions& options) {
  const cv::Mat image = RenderPlot(series, options);
  WriteImageAtomically(path, image);
}

}  // namespace dvso
