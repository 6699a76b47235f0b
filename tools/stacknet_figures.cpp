// Figures of the StackNet training pipeline (scripts/train_stacknet.sh):
//   stacknet_figures montage --out F.png [--titles a,b,c,d] [--scale-width W]
//                            --row IMAGE GT PRED1 PRED2 [--row ...]
//     side-by-side rows: the colour image, then disparity maps (KITTI uint16
//     PNG) colour-mapped with one scale per row (the GT's 99th percentile);
//     GT zero (sky / invalid) is black; GT "-" = none (real images; scale from
//     the first prediction).
//   stacknet_figures curve --csv RUN/curve.csv --out F.png
//     learning curve: mean training loss per epoch and held-out abs rel per
//     evaluated epoch, against the global step, stage boundaries marked.
#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/plot.h"

namespace {

using dvso::Require;

constexpr int kTileWidth = 480;        // pixels per montage tile (height keeps the aspect)
constexpr int kTitleHeight = 28;       // title band above each column
constexpr double kScalePercentile = 0.99;  // colour scale: this percentile of the row's GT disparity

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);) out.push_back(item);
  return out;
}

cv::Mat Colourise(const cv::Mat& disparity, double scale, const cv::Size& size) {
  cv::Mat resized;
  cv::resize(disparity, resized, size, 0, 0, cv::INTER_NEAREST);
  cv::Mat normalized;
  resized.convertTo(normalized, CV_8U, 255.0 / scale);
  cv::Mat coloured;
  cv::applyColorMap(normalized, coloured, cv::COLORMAP_MAGMA);
  coloured.setTo(cv::Scalar(0, 0, 0), resized <= 0);
  return coloured;
}

int Montage(const std::string& out, const std::vector<std::string>& titles, const std::vector<std::vector<std::string>>& rows) {
  Require(!rows.empty(), "montage needs at least one --row");
  std::vector<cv::Mat> lines;
  const size_t columns = rows.front().size();
  cv::Size tile;
  for (const auto& row : rows) {
    Require(row.size() == columns && columns >= 2, "every --row needs the same number (>= 2) of files");
    const cv::Mat image = cv::imread(row[0], cv::IMREAD_COLOR);
    dvso::RequireFile(!image.empty(), row[0], "cannot read image");
    tile = cv::Size(kTileWidth, kTileWidth * image.rows / image.cols);
    std::vector<cv::Mat> tiles;
    cv::Mat resized;
    cv::resize(image, resized, tile, 0, 0, cv::INTER_AREA);
    tiles.push_back(resized);
    // "-" as GT: no ground truth (real images); the scale comes from the first prediction.
    const bool no_gt = row[1] == "-";
    Require(!no_gt || columns >= 3, "a row without GT needs a prediction");
    const cv::Mat gt = dvso::ReadKittiMapPng(no_gt ? row[2] : row[1]);
    std::vector<float> values;
    for (auto it = gt.begin<float>(); it != gt.end<float>(); ++it)
      if (*it > 0) values.push_back(*it);
    double scale = 1;
    if (!values.empty()) {
      const size_t k = static_cast<size_t>(values.size() * kScalePercentile);
      std::nth_element(values.begin(), values.begin() + std::min(k, values.size() - 1), values.end());
      scale = std::max(1.0, static_cast<double>(values[std::min(k, values.size() - 1)]));
    }
    for (size_t c = 1; c < columns; ++c) {
      if (c == 1 && no_gt) {
        tiles.push_back(cv::Mat(tile, CV_8UC3, cv::Scalar(40, 40, 40)));
        cv::putText(tiles.back(), "no GT", cv::Point(10, tile.height / 2), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                    cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
        continue;
      }
      tiles.push_back(Colourise(dvso::ReadKittiMapPng(row[c]), scale, tile));
    }
    cv::Mat line;
    cv::hconcat(tiles, line);
    lines.push_back(line);
  }
  cv::Mat header(kTitleHeight, static_cast<int>(tile.width * columns), CV_8UC3, cv::Scalar(255, 255, 255));
  for (size_t c = 0; c < columns && c < titles.size(); ++c)
    cv::putText(header, titles[c], cv::Point(static_cast<int>(c * tile.width) + 8, kTitleHeight - 8),
                cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  lines.insert(lines.begin(), header);
  cv::Mat all;
  cv::vconcat(lines, all);
  dvso::RequireFile(cv::imwrite(out, all), out, "cannot write PNG");
  std::cout << "wrote " << out << " (" << all.cols << "x" << all.rows << ")\n";
  return 0;
}

int Curve(const std::string& csv_path, const std::string& out) {
  std::ifstream in(csv_path);
  dvso::RequireFile(in.good(), csv_path, "cannot read");
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = Split(line, ',');
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  for (const char* name : {"global_step", "mean_total", "mean_supervised", "abs_rel", "stage"})
    dvso::RequireFile(column.count(name) > 0, csv_path, std::string("no column ") + name);
  dvso::PlotSeries loss, supervised, abs_rel;
  loss.label = "mean training loss (total)";
  loss.color = cv::Scalar(200, 80, 0);
  loss.markers = true;
  supervised.label = "mean L_S term";
  supervised.color = cv::Scalar(0, 150, 0);
  supervised.markers = true;
  abs_rel.label = "held-out abs rel";
  abs_rel.color = cv::Scalar(0, 0, 200);
  abs_rel.markers = true;
  std::vector<double> stage_starts;
  std::string last_stage;
  double previous_step = 0;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = Split(line, ',');
    if (f.size() < header.size() - 4) continue;
    auto value = [&](const char* name) {
      const size_t i = column[name];
      return i < f.size() && !f[i].empty() ? std::stod(f[i]) : std::numeric_limits<double>::quiet_NaN();
    };
    const double step = value("global_step");
    if (f[column["stage"]] != last_stage) {
      if (!last_stage.empty()) stage_starts.push_back(previous_step);
      last_stage = f[column["stage"]];
    }
    previous_step = step;
    loss.x.push_back(step);
    loss.y.push_back(value("mean_total"));
    supervised.x.push_back(step);
    supervised.y.push_back(value("mean_supervised"));
    const double a = value("abs_rel");
    if (std::isfinite(a)) {
      abs_rel.x.push_back(step);
      abs_rel.y.push_back(a);
    }
  }
  Require(!loss.x.empty(), "the learning-curve CSV has no rows");
  std::vector<cv::Mat> panels;
  dvso::PlotOptions top;
  top.width = 900;
  top.height = 380;
  top.title = "StackNet training: mean loss per epoch (stage ends dotted)";
  top.x_label = "step";
  top.include_zero_y = true;
  std::vector<dvso::PlotSeries> losses = {loss, supervised};
  for (double s : stage_starts) {
    dvso::PlotSeries marker;
    marker.x = {s, s};
    marker.y = {0.0, *std::max_element(loss.y.begin(), loss.y.end())};
    marker.color = cv::Scalar(150, 150, 150);
    marker.thickness = 1;
    losses.push_back(marker);
  }
  panels.push_back(dvso::RenderPlot(losses, top));
  if (!abs_rel.x.empty()) {
    dvso::PlotOptions bottom = top;
    bottom.title = "held-out abs rel (KITTI 08/09/10 sims, every 5th frame, 0-80 m)";
    panels.push_back(dvso::RenderPlot({abs_rel}, bottom));
  }
  cv::Mat all;
  cv::vconcat(panels, all);
  dvso::RequireFile(cv::imwrite(out, all), out, "cannot write PNG");
  std::cout << "wrote " << out << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<std::string> args(argv + 1, argv + argc);
    Require(!args.empty(), "usage: stacknet_figures montage|curve ...");
    std::string out, csv;
    std::vector<std::string> titles;
    std::vector<std::vector<std::string>> rows;
    for (size_t i = 1; i < args.size(); ++i) {
      if (args[i] == "--out" && i + 1 < args.size()) {
        out = args[++i];
      } else if (args[i] == "--csv" && i + 1 < args.size()) {
        csv = args[++i];
      } else if (args[i] == "--titles" && i + 1 < args.size()) {
        titles = Split(args[++i], ',');
      } else if (args[i] == "--row") {
        std::vector<std::string> row;
        while (i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0) row.push_back(args[++i]);
        rows.push_back(row);
      } else {
        throw dvso::Error("unknown argument " + args[i]);
      }
    }
    Require(!out.empty(), "give --out");
    if (args[0] == "montage") return Montage(out, titles, rows);
    if (args[0] == "curve") return Curve(csv, out);
    throw dvso::Error("unknown figure " + args[0] + " (montage or curve)");
  } catch (const std::exception& e) {
    std::cerr << "stacknet_figures: error: " << e.what() << "\n";
    return 1;
  }
}
