#pragma once
/// \file eval_report.hpp
/// `gseg eval`: aggregation of scored frames per sequence and the report texts (CSV, Markdown,
/// printed summary). Core-only (no MRPT), so the tests compile it with hand-made scores.

#include <gseg/eval/breakdown.hpp>
#include <gseg/eval/metrics.hpp>
#include <gseg/io/bytes.hpp>

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace gseg::app {

/// One scored frame.
struct FrameRow {
    std::string sequence;  ///< e.g. "00"
    std::string name;      ///< file stem, e.g. "000000"
    std::size_t points = 0;
    FrameScore score;      ///< from gseg::scoreFrame (GSB protocol)
    double ms = 0;         ///< [ms] time of the segment() call
    Breakdown breakdown;   ///< where the errors are (filled with --breakdown)
};

/// A scored frame as bytes and back, exactly (the reports of a run spread over MPI ranks equal a
/// serial run's). readRow() throws std::runtime_error on a short message.
void writeRow(io::ByteWriter& out, const FrameRow& row);
FrameRow readRow(io::ByteReader& in);

/// One sequence. Precision / recall / F1 are in %, averaged over frames as GSB does (per-frame
/// ratios, then their mean; frames where a ratio is undefined are left out of that mean).
struct SequenceSummary {
    std::string sequence;
    std::size_t frames = 0;
    Counts sum;                          ///< withVegetation counts summed over the frames
    Counts sumNoVeg;                     ///< withoutVegetation counts summed over the frames
    MeanStd p, r, f1;                    ///< over frames, no range cut, with vegetation
    MeanStd pNoVeg, rNoVeg, f1NoVeg;     ///< over frames, no range cut, without vegetation
    std::array<double, 10> rangeP{}, rangeR{}, rangeF1{};  ///< at each range limit: mean over frames (F1 of those two)
    MeanStd rangePStats, rangeRStats, rangeF1Stats;        ///< over the ten limits: the paper's Table II figures
    double ms = 0;                       ///< [ms] mean time per frame
    Breakdown breakdown;                 ///< summed over the frames
};

/// Groups `frames` by sequence (sorted by name) and aggregates each group.
std::vector<SequenceSummary> summarise(const std::vector<FrameRow>& frames);

/// Per-frame CSV: sequence,frame,points,TP,FP,FN,precision,recall,F1,precision_noveg,recall_noveg,ms
/// (counts and ratios with vegetation unless named _noveg; ms is the last column).
std::string framesCsv(const std::vector<FrameRow>& frames);

/// Per-sequence CSV: frame means, summed counts, range-limited mean/std and the ten limits.
std::string sequencesCsv(const std::vector<SequenceSummary>& seqs);

/// The paper's Table II layout: per sequence Pr. / Rc. / F1 as mean ± std over the range limits,
/// the no-range-cut figures and ms/scan, then the mean over sequences.
std::string markdownTable(const std::vector<SequenceSummary>& seqs);

/// One printed line per sequence.
std::string summaryText(const std::vector<SequenceSummary>& seqs);

/// Failure breakdown CSV, long format: sequence,frame,kind,bin,points. kind is false_by_class,
/// false_by_height (above the local labelled ground), false_by_range, missed_by_class or
/// missed_by_range; a sequence's sum has frame "all", the run's sum sequence "all".
std::string breakdownCsv(const std::vector<FrameRow>& frames, const std::vector<SequenceSummary>& seqs);

/// The run's breakdown as a printed table (points and share of the false / missed ground), per
/// sequence and for all frames.
std::string breakdownText(const std::vector<SequenceSummary>& seqs);

}  // namespace gseg::app
