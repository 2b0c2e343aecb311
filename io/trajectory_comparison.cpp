#include "jpcr/io/trajectory_comparison.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// Squared errors of the common pairs, in the baseline's order (consecutive in the sequence).
struct CommonPairs {
  std::vector<double> t_est, t_base, r_est, r_base;
};

CommonPairs common_pairs(const RelativeErrors& estimate, const RelativeErrors& baseline) {
  std::map<std::pair<std::size_t, std::size_t>, std::size_t> index;
  for (std::size_t i = 0; i < estimate.ground_truth_frames.size(); ++i)
    index.emplace(estimate.ground_truth_frames[i], i);
  CommonPairs c;
  for (std::size_t j = 0; j < baseline.ground_truth_frames.size(); ++j) {
    const auto found = index.find(baseline.ground_truth_frames[j]);
    if (found == index.end()) continue;
    const std::size_t i = found->second;
    c.t_est.push_back(estimate.translation[i] * estimate.translation[i]);
    c.t_base.push_back(baseline.translation[j] * baseline.translation[j]);
    c.r_est.push_back(estimate.rotation[i] * estimate.rotation[i]);
    c.r_base.push_back(baseline.rotation[j] * baseline.rotation[j]);
  }
  return c;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(at);
  const double f = at - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1.0 - f) + v[i + 1] * f : v[i];
}

double sum(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v)
    s += x;
  return s;
}

}  // namespace

const char* RatioInterval::verdict() const {
  if (high < 1.0) return "better";
  if (low > 1.0) return "worse";
  return "indistinguishable";
}

PairedComparison compare_relative_errors(const RelativeErrors& estimate,
                                         const RelativeErrors& baseline, int resamples,
                                         std::uint64_t seed) {
  if (resamples < 1) throw InputError("bootstrap: resamples must be at least 1");
  const CommonPairs c = common_pairs(estimate, baseline);
  const std::size_t n = c.t_est.size();
  if (n < 10)
    throw InputError("only " + std::to_string(n) +
                     " frame pairs are common to the estimate and the baseline (need 10)");
  if (!(sum(c.t_base) > 0.0) || !(sum(c.r_base) > 0.0))
    throw InputError("the baseline's relative errors are all zero: no ratio to form");
  PairedComparison out;
  out.pairs = n;
  out.block = static_cast<std::size_t>(std::ceil(std::cbrt(static_cast<double>(n))));
  out.translation.ratio = std::sqrt(sum(c.t_est) / sum(c.t_base));
  out.rotation.ratio = std::sqrt(sum(c.r_est) / sum(c.r_base));
  // Moving-block bootstrap: n / block blocks of `block` consecutive pairs, starts uniform.
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> start(0, n - out.block);
  std::vector<double> t_ratios, r_ratios;
  for (int b = 0; b < resamples; ++b) {
    double te = 0.0, tb = 0.0, re = 0.0, rb = 0.0;
    for (std::size_t drawn = 0; drawn < n; drawn += out.block) {
      const std::size_t s = start(rng);
      for (std::size_t k = s; k < s + out.block; ++k) {
        te += c.t_est[k];
        tb += c.t_base[k];
        re += c.r_est[k];
        rb += c.r_base[k];
      }
    }
    if (tb > 0.0) t_ratios.push_back(std::sqrt(te / tb));
    if (rb > 0.0) r_ratios.push_back(std::sqrt(re / rb));
  }
  const auto interval = [](RatioInterval& r, const std::vector<double>& ratios) {
    if (ratios.empty()) return;
    r.low = quantile(ratios, 0.025);
    r.high = quantile(ratios, 0.975);
  };
  interval(out.translation, t_ratios);
  interval(out.rotation, r_ratios);
  return out;
}

}  // namespace jpcr
