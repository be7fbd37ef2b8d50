#pragma once
/// \file eval_plot.hpp
/// `gseg eval`: PNG plot of precision and recall against the range limit, one colour per sequence.

#include "eval_report.hpp"

#include <string>
#include <vector>

namespace gseg::app {

/// Draws the range-limited precision (thick lines) and recall (thin lines, squares) of every
/// sequence against the range limit 10..100 m and writes the PNG atomically (temp + rename).
/// Throws std::runtime_error if the file cannot be written.
void plotRanges(const std::string& path, const std::vector<SequenceSummary>& seqs);

}  // namespace gseg::app
