#pragma once
/// \file eval_plot.hpp
/// `gseg eval`: PNG plot of precision and recall against the range limit, one colour per sequence.

#include "eval_report.hpp"

#include <gseg/eval/breakdown.hpp>
#include <gseg/point_cloud.hpp>

#include <string>
#include <vector>

namespace gseg::app {

/// Draws the range-limited precision (thick lines) and recall (thin lines, squares) of every
/// sequence against the range limit 10..100 m: the PNG's bytes.
std::string rangePlotPng(const std::vector<SequenceSummary>& seqs);

/// Top-down picture of one scored frame (sensor at the centre, x forward up, y left to the left, as
/// `gseg segment` draws): true ground green, false ground red, missed ground blue, other points
/// grey; title, legend with counts, a scale bar and the forward arrow. Written atomically.
void plotOutcomes(const std::string& path, const PointCloudView& cloud, const std::vector<PointOutcome>& outcomes,
                  const std::string& title);

}  // namespace gseg::app
