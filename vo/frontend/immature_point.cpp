#include "vo/frontend/immature_point.h"

#include <cmath>

#include "core/error.h"
#include "vo/optimization/photometric_kernel.h"

namespace dvso::vo {

void ImmaturePointOptions::Check() const {
  Require(huber_threshold > 0, "immature huber_threshold must be > 0");
  Require(outlier_energy_per_pixel > 0, "immature outlier_energy_per_pixel must be > 0");
  Require(extra_slack_on_threshold >= 1, "immature extra_slack_on_threshold must be >= 1");
  Require(max_search_fraction > 0, "immature max_search_fraction must be > 0");
  Require(step_size > 0, "immature step_size must be > 0");
  Require(slack_interval > 0, "immature slack_interval must be > 0");
  Require(min_improvement_factor >= 1, "immature min_improvement_factor must be >= 1");
  Require(gn_iterations >= 0, "immature gn_iterations must be >= 0");
  Require(min_quality >= 1, "immature min_quality must be >= 1");
  Require(max_pixel_interval > 0, "immature max_pixel_interval must be > 0");
}

bool ImmaturePoint::Initialize(const PyramidLevel& host, int host_id_in, float u_in, float v_in, int level) {
  host_id = host_id_in;
  u = u_in;
  v = v_in;
  selection_level = level;
  gradient_h.setZero();
  const float border = kPatternRadius + 2.0f;
  if (!host.InBounds(u, v, border)) return false;
  for (int k = 0; k < kPatternSize; ++k) {
    const Eigen::Vector3f c = host.Interpolate(u + kPatternOffsets[k][0], v + kPatternOffsets[k][1]);
    color[k] = c[0];
    const Eigen::Vector2f g = c.tail<2>();
    gradient_h += g * g.transpose();
  }
  return gradient_h.trace() > 1e-6f;
}

void ImmaturePoint::SetPredictedInterval(float idepth, float relative_range, bool converged) {
  idepth_min = idepth * (1.0f - relative_range);
  idepth_max = idepth * (1.0f + relative_range);
  if (!converged) return;
  // What a successful, unambiguous search would have left behind.
  last_status = TraceStatus::kGood;
  last_pixel_interval = 0.0f;
  quality = std::numeric_limits<float>::max();
}

bool ImmaturePoint::ReadyForActivation(const ImmaturePointOptions& options) const {
  // DSO activatePointsMT: a skipped / badly conditioned last search keeps the
  // interval of the previous good one.
  const bool status_ok = last_status == TraceStatus::kGood || last_status == TraceStatus::kSkipped ||
                         last_status == TraceStatus::kBadCondition;
  return status_ok && HasFiniteInterval() && idepth_min >= 0 &&
         last_pixel_interval < options.max_pixel_interval && quality > options.min_quality;
}

TraceStatus ImmaturePoint::Trace(const PyramidLevel& target, const Eigen::Matrix3f& KRKi, const Eigen::Vector3f& Kt,
                                 float a, float b, const ImmaturePointOptions& opt, float max_search_px) {
  if (last_status == TraceStatus::kOutOfBounds) return last_status;
  const float border = kPatternRadius + 2.0f;
  const Eigen::Vector3f pr = KRKi * Eigen::Vector3f(u, v, 1.0f);
  const Eigen::Vector3f ptp_min = pr + Kt * idepth_min;
  if (!(ptp_min.z() > 1e-6f)) return last_status = TraceStatus::kOutOfBounds;
  const float u_min = ptp_min.x() / ptp_min.z();
  const float v_min = ptp_min.y() / ptp_min.z();
  if (!target.InBounds(u_min, v_min, border)) return last_status = TraceStatus::kOutOfBounds;

  float dist, u_max, v_max;
  float dir_u = 0.0f, dir_v = 0.0f;  // unit direction of an unbounded search (exact: (-1, 0) for static stereo)
  if (HasFiniteInterval()) {
    const Eigen::Vector3f ptp_max = pr + Kt * idepth_max;
    if (!(ptp_max.z() > 1e-6f)) return last_status = TraceStatus::kOutOfBounds;
    u_max = ptp_max.x() / ptp_max.z();
    v_max = ptp_max.y() / ptp_max.z();
    if (!target.InBounds(u_max, v_max, border)) return last_status = TraceStatus::kOutOfBounds;
    dist = std::hypot(u_min - u_max, v_min - v_max);
    if (dist < opt.slack_interval) {
      last_pixel_interval = dist;
      return last_status = TraceStatus::kSkipped;
    }
  } else {
    const float search = max_search_px > 0 ? max_search_px
                                           : static_cast<float>(opt.max_search_fraction * (target.width + target.height));
    // Direction of the epipolar line: towards larger inverse depth.
    const Eigen::Vector3f ptp_far = pr + Kt * (idepth_min + 0.01f);
    float du = ptp_far.x() / ptp_far.z() - u_min;
    float dv = ptp_far.y() / ptp_far.z() - v_min;
    const float n = std::hypot(du, dv);
    if (!(n > 1e-9f)) return last_status = TraceStatus::kBadCondition;  // no translation: no depth information
    dir_u = du / n;
    dir_v = dv / n;
    u_max = u_min + search * dir_u;
    v_max = v_min + search * dir_v;
    dist = search;
    // Clip the segment to the image.
    if (!target.InBounds(u_max, v_max, border)) {
      float lo = 0, hi = 1;
      for (int it = 0; it < 20; ++it) {
        const float mid = 0.5f * (lo + hi);
        if (target.InBounds(u_min + mid * (u_max - u_min), v_min + mid * (v_max - v_min), border)) lo = mid; else hi = mid;
      }
      u_max = u_min + lo * (u_max - u_min);
      v_max = v_min + lo * (v_max - v_min);
      dist *= lo;
      if (dist < 1.0f) return last_status = TraceStatus::kOutOfBounds;
    }
  }

  // Expected pixel error of a match along direction (dx, dy): large when the
  // image gradient is perpendicular to the epipolar line (DSO's error model).
  const bool unbounded = dir_u != 0.0f || dir_v != 0.0f;
  const float dx_unit = unbounded ? dir_u : (u_max - u_min) / dist;
  const float dy_unit = unbounded ? dir_v : (v_max - v_min) / dist;
  const Eigen::Vector2f along(dx_unit, dy_unit), perp(dy_unit, -dx_unit);
  const float ga = along.dot(gradient_h * along);
  const float gb = perp.dot(gradient_h * perp);
  float error_px = 0.2f + 0.2f * (ga + gb) / std::max(ga, 1e-6f);
  if (error_px * opt.min_improvement_factor > dist && HasFiniteInterval()) {
    last_pixel_interval = dist;
    return last_status = TraceStatus::kBadCondition;
  }
  error_px = std::min(error_px, 10.0f);

  // Discrete search.
  const float energy_th = static_cast<float>(kPatternSize * opt.outlier_energy_per_pixel * opt.extra_slack_on_threshold);
  const float step = static_cast<float>(opt.step_size);
  // Every sample of the segment (DSO capped it at 100 steps, the size of its fixed array: with a static
  // stereo search of 0.2 x 1241 px that cut off every disparity above 100 px, i.e. depths below 3.9 m on
  // KITTI, and the far end's true match was replaced by a wrong one within the first 100 px).
  const int num_steps = static_cast<int>(1.9999f + dist / step);
  const float sx = dx_unit * step, sy = dy_unit * step;
  const float huber = static_cast<float>(opt.huber_threshold);
  float best_energy = 1e10f, second_energy = 1e10f;
  int best_idx = -1;
  std::vector<float> energies(num_steps);
  float cu = u_min, cv = v_min;
  // Static stereo from an integer pixel walks integer positions along the
  // row: read the pixels directly (what the bilinear interpolation returns
  // there anyway, at a quarter of the memory traffic).
  const bool integral_walk = sy == 0.0f && sx == std::round(sx) && cu == std::floor(cu) && cv == std::floor(cv);
  for (int i = 0; i < num_steps; ++i, cu += sx, cv += sy) {
    float e = 0;
    if (!target.InBounds(cu, cv, border)) {
      e = 1e10f;
    } else if (integral_walk) {
      const Eigen::Vector3f* centre =
          target.data.data() + static_cast<size_t>(cv) * target.width + static_cast<size_t>(cu);
      for (int k = 0; k < kPatternSize && e < energy_th; ++k) {
        const float hit = centre[kPatternOffsets[k][1] * target.width + kPatternOffsets[k][0]][0];
        e += HuberEnergy(hit - (a * color[k] + b), huber);
      }
    } else {
      // Early exit above the outlier threshold: such a sample can be neither a
      // valid match nor a meaningful second best (its energy stays a lower
      // bound, which only lowers the quality: conservative).
      for (int k = 0; k < kPatternSize && e < energy_th; ++k) {
        const float hit = target.InterpolateIntensity(cu + kPatternOffsets[k][0], cv + kPatternOffsets[k][1]);
        e += HuberEnergy(hit - (a * color[k] + b), huber);
      }
    }
    energies[i] = e;
    if (e < best_energy) {
      best_energy = e;
      best_idx = i;
    }
  }
  if (best_idx < 0) return last_status = TraceStatus::kOutOfBounds;
  const int radius = static_cast<int>(std::ceil(opt.min_test_radius / step));
  for (int i = 0; i < num_steps; ++i) {
    if (std::abs(i - best_idx) > radius && energies[i] < second_energy) second_energy = energies[i];
  }
  const float new_quality = second_energy / std::max(best_energy, 1e-6f);
  // DSO: keep the lowest quality seen, but a long search (fresh, wide interval) resets it.
  if (new_quality < quality || num_steps > 10) quality = new_quality;

  // Gauss-Newton refinement of the step parameter along the line.
  float best_u = u_min + best_idx * sx, best_v = v_min + best_idx * sy;
  for (int it = 0; it < opt.gn_iterations; ++it) {
    float H = 1e-6f, g = 0, e = 0;
    bool ok = true;
    for (int k = 0; k < kPatternSize; ++k) {
      const float px = best_u + kPatternOffsets[k][0], py = best_v + kPatternOffsets[k][1];
      if (!target.InBounds(px, py, 1.5f)) {
        ok = false;
        break;
      }
      const Eigen::Vector3f hit = target.Interpolate(px, py);
      const float r = hit[0] - (a * color[k] + b);
      const float hw = std::fabs(r) < huber ? 1.0f : huber / std::fabs(r);
      const float dres = dx_unit * hit[1] + dy_unit * hit[2];
      H += hw * dres * dres;
      g += hw * r * dres;
      e += HuberEnergy(r, huber);
    }
    if (!ok) break;
    float delta = -g / H;
    delta = std::max(-0.5f, std::min(0.5f, delta));
    if (!std::isfinite(delta)) break;
    best_u += delta * dx_unit;
    best_v += delta * dy_unit;
    best_energy = std::min(best_energy, e);
    if (std::fabs(delta) < opt.gn_threshold) break;
  }
  last_energy = best_energy;

  if (!(best_energy < energy_th)) {
    // Two outliers in a row: drop (DSO).
    if (last_status == TraceStatus::kOutlier) return last_status = TraceStatus::kOutOfBounds;
    return last_status = TraceStatus::kOutlier;
  }

  // Interval from the match +- the expected error, converted to inverse depth
  // along the better-conditioned image axis.
  auto idepth_at = [&](float pu, float pv) {
    if (std::fabs(dx_unit) > std::fabs(dy_unit)) return (pr.x() - pu * pr.z()) / (pu * Kt.z() - Kt.x());
    return (pr.y() - pv * pr.z()) / (pv * Kt.z() - Kt.y());
  };
  float id_a = idepth_at(best_u - error_px * dx_unit, best_v - error_px * dy_unit);
  float id_b = idepth_at(best_u + error_px * dx_unit, best_v + error_px * dy_unit);
  if (id_a > id_b) std::swap(id_a, id_b);
  if (!std::isfinite(id_a) || !std::isfinite(id_b) || id_b <= 0) {
    return last_status = TraceStatus::kOutlier;
  }
  idepth_min = std::max(0.0f, id_a);
  idepth_max = id_b;
  last_pixel_interval = 2 * error_px;
  return last_status = TraceStatus::kGood;
}

}  // namespace dvso::vo
