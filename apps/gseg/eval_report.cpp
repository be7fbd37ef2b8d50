// gseg eval: per-sequence aggregation and report texts.
#include "eval_report.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <algorithm>
#include <map>

namespace gseg::app {
namespace {

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
    char buf[512];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, args);
    va_end(args);
    return buf;
}

double f1Of(double p, double r) { return (std::isnan(p) || std::isnan(r) || p + r == 0) ? NAN : 2 * p * r / (p + r); }

/// "12.34 ± 0.56", or "n/a" when undefined.
std::string pm(const MeanStd& m) { return std::isnan(m.mean) ? "n/a" : format("%.2f ± %.2f", m.mean, m.stddev); }
std::string num(double v, const char* fmt = "%.2f") { return std::isnan(v) ? "n/a" : format(fmt, v); }

unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }

SequenceSummary summariseOne(const std::string& name, const std::vector<const FrameRow*>& rows) {
    SequenceSummary s;
    s.sequence = name;
    s.frames = rows.size();
    std::vector<double> p, r, f, pn, rn, fn;
    double ms = 0;
    for (const FrameRow* row : rows) {
        const Counts &c = row->score.withVegetation, &n = row->score.withoutVegetation;
        s.sum += c, s.sumNoVeg += n;
        p.push_back(c.precision()), r.push_back(c.recall()), f.push_back(c.f1());
        pn.push_back(n.precision()), rn.push_back(n.recall()), fn.push_back(n.f1());
        ms += row->ms;
        s.breakdown += row->breakdown;
    }
    s.p = meanStd(p), s.r = meanStd(r), s.f1 = meanStd(f);
    s.pNoVeg = meanStd(pn), s.rNoVeg = meanStd(rn), s.f1NoVeg = meanStd(fn);
    s.ms = rows.empty() ? 0 : ms / double(rows.size());
    for (std::size_t k = 0; k < s.rangeP.size(); ++k) {
        std::vector<double> pk, rk;
        for (const FrameRow* row : rows) {
            pk.push_back(row->score.byRange[k].precision());
            rk.push_back(row->score.byRange[k].recall());
        }
        s.rangeP[k] = meanStd(pk).mean, s.rangeR[k] = meanStd(rk).mean;
        s.rangeF1[k] = f1Of(s.rangeP[k], s.rangeR[k]);
    }
    auto overLimits = [](const std::array<double, 10>& a) { return meanStd(std::vector<double>(a.begin(), a.end())); };
    s.rangePStats = overLimits(s.rangeP), s.rangeRStats = overLimits(s.rangeR), s.rangeF1Stats = overLimits(s.rangeF1);
    return s;
}

}  // namespace

namespace {

void writeCounts(io::ByteWriter& out, const Counts& c) { out.u64(c.tp).u64(c.fp).u64(c.fn).u64(c.tn); }
Counts readCounts(io::ByteReader& in) {
    Counts c;
    c.tp = in.u64(), c.fp = in.u64(), c.fn = in.u64(), c.tn = in.u64();
    return c;
}

void writeClasses(io::ByteWriter& out, const std::map<std::uint32_t, std::uint64_t>& m) {
    out.u64(m.size());
    for (const auto& [id, n] : m) out.u64(id).u64(n);
}
std::map<std::uint32_t, std::uint64_t> readClasses(io::ByteReader& in) {
    std::map<std::uint32_t, std::uint64_t> m;
    for (std::uint64_t k = in.u64(); k > 0; --k) {
        const auto id = std::uint32_t(in.u64());
        m[id] = in.u64();
    }
    return m;
}

template <std::size_t N>
void writeBins(io::ByteWriter& out, const std::array<std::uint64_t, N>& a) {
    for (const std::uint64_t v : a) out.u64(v);
}
template <std::size_t N>
void readBins(io::ByteReader& in, std::array<std::uint64_t, N>& a) {
    for (std::uint64_t& v : a) v = in.u64();
}

}  // namespace

void writeRow(io::ByteWriter& out, const FrameRow& row) {
    out.str(row.sequence).str(row.name).u64(row.points).f64(row.ms);
    const FrameScore& s = row.score;
    out.u64(s.points);
    writeCounts(out, s.withVegetation), writeCounts(out, s.withoutVegetation);
    for (const Counts& c : s.byRange) writeCounts(out, c);
    const Breakdown& b = row.breakdown;
    writeClasses(out, b.falseByClass), writeClasses(out, b.missedByClass);
    writeBins(out, b.falseByHeight), writeBins(out, b.falseByRange), writeBins(out, b.missedByRange);
    out.u64(b.falseGround).u64(b.missedGround).u64(b.trueGround);
}

FrameRow readRow(io::ByteReader& in) {
    FrameRow row;
    row.sequence = in.str(), row.name = in.str();
    row.points = std::size_t(in.u64());
    row.ms = in.f64();
    FrameScore& s = row.score;
    s.points = std::size_t(in.u64());
    s.withVegetation = readCounts(in), s.withoutVegetation = readCounts(in);
    for (Counts& c : s.byRange) c = readCounts(in);
    Breakdown& b = row.breakdown;
    b.falseByClass = readClasses(in), b.missedByClass = readClasses(in);
    readBins(in, b.falseByHeight), readBins(in, b.falseByRange), readBins(in, b.missedByRange);
    b.falseGround = in.u64(), b.missedGround = in.u64(), b.trueGround = in.u64();
    return row;
}

std::vector<SequenceSummary> summarise(const std::vector<FrameRow>& frames) {
    std::map<std::string, std::vector<const FrameRow*>> bySeq;
    for (const FrameRow& f : frames) bySeq[f.sequence].push_back(&f);
    std::vector<SequenceSummary> out;
    for (const auto& [name, rows] : bySeq) out.push_back(summariseOne(name, rows));
    return out;
}

std::string framesCsv(const std::vector<FrameRow>& frames) {
    std::string o = "sequence,frame,points,TP,FP,FN,precision,recall,F1,precision_noveg,recall_noveg,ms\n";
    for (const FrameRow& f : frames) {
        const Counts &c = f.score.withVegetation, &n = f.score.withoutVegetation;
        o += format("%s,%s,%zu,%llu,%llu,%llu,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f\n", f.sequence.c_str(), f.name.c_str(),
                    f.points, ull(c.tp), ull(c.fp), ull(c.fn), c.precision(), c.recall(), c.f1(), n.precision(),
                    n.recall(), f.ms);
    }
    return o;
}

std::string sequencesCsv(const std::vector<SequenceSummary>& seqs) {
    std::string o = "sequence,frames,TP,FP,FN,precision,recall,F1,precision_noveg,recall_noveg,F1_noveg,"
                    "range_precision_mean,range_precision_std,range_recall_mean,range_recall_std,"
                    "range_F1_mean,range_F1_std,ms";
    for (int d = 10; d <= 100; d += 10) o += format(",P<%dm,R<%dm", d, d);
    o += "\n";
    for (const SequenceSummary& s : seqs) {
        o += format("%s,%zu,%llu,%llu,%llu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f", s.sequence.c_str(), s.frames, ull(s.sum.tp),
                    ull(s.sum.fp), ull(s.sum.fn), s.p.mean, s.r.mean, s.f1.mean, s.pNoVeg.mean, s.rNoVeg.mean,
                    s.f1NoVeg.mean);
        o += format(",%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f", s.rangePStats.mean, s.rangePStats.stddev,
                    s.rangeRStats.mean, s.rangeRStats.stddev, s.rangeF1Stats.mean, s.rangeF1Stats.stddev, s.ms);
        for (std::size_t k = 0; k < s.rangeP.size(); ++k) o += format(",%.4f,%.4f", s.rangeP[k], s.rangeR[k]);
        o += "\n";
    }
    return o;
}

std::string markdownTable(const std::vector<SequenceSummary>& seqs) {
    std::string o = "| Seq. | frames | Pr. (%) | Rc. (%) | F1 (%) | Pr. no range cut | Rc. no range cut | ms/scan |\n"
                     "|---|---|---|---|---|---|---|---|\n";
    std::vector<double> p, r, f, p0, r0, ms;
    for (const SequenceSummary& s : seqs) {
        o += format("| %s | %zu | %s | %s | %s | %s | %s | %.1f |\n", s.sequence.c_str(), s.frames,
                    pm(s.rangePStats).c_str(), pm(s.rangeRStats).c_str(), pm(s.rangeF1Stats).c_str(),
                    num(s.p.mean).c_str(), num(s.r.mean).c_str(), s.ms);
        p.push_back(s.rangePStats.mean), r.push_back(s.rangeRStats.mean), f.push_back(s.rangeF1Stats.mean);
        p0.push_back(s.p.mean), r0.push_back(s.r.mean), ms.push_back(s.ms);
    }
    o += format("| **mean** | %zu seq. | **%s** | **%s** | **%s** | %s | %s | %.1f |\n", seqs.size(),
                num(meanStd(p).mean).c_str(), num(meanStd(r).mean).c_str(), num(meanStd(f).mean).c_str(),
                num(meanStd(p0).mean).c_str(), num(meanStd(r0).mean).c_str(), meanStd(ms).mean);
    o += "\nPr. / Rc.: per sequence, the mean over frames of each frame's precision / recall within a horizontal "
         "range limit, then mean ± std over the limits 10, 20, ..., 100 m (GSB protocol, low vegetation is ground). "
         "F1: of those means at each limit, then mean ± std over the limits. No range cut: all points. ms/scan: mean "
         "time of a warm segment() call in this run (parallel workers share the cores; see gseg bench).\n";
    return o;
}

std::string summaryText(const std::vector<SequenceSummary>& seqs) {
    std::string o;
    for (const SequenceSummary& s : seqs)
        o += format("sequence %s: %zu frames, TP %llu FP %llu FN %llu; P %s R %s F1 %s (no range cut; without "
                    "vegetation P %s R %s); range-limited P %s R %s F1 %s; %.1f ms/scan\n",
                    s.sequence.c_str(), s.frames, ull(s.sum.tp), ull(s.sum.fp), ull(s.sum.fn), num(s.p.mean).c_str(),
                    num(s.r.mean).c_str(), num(s.f1.mean).c_str(), num(s.pNoVeg.mean).c_str(),
                    num(s.rNoVeg.mean).c_str(), pm(s.rangePStats).c_str(), pm(s.rangeRStats).c_str(),
                    pm(s.rangeF1Stats).c_str(), s.ms);
    return o;
}

namespace {

/// Visits every (kind, bin, points) of a breakdown, in a fixed order.
template <typename Fn>
void forEachBin(const Breakdown& b, Fn&& fn) {
    for (const auto& [id, n] : b.falseByClass) fn("false_by_class", semanticClassName(id), n);
    for (int k = 0; k < HeightBins::kCount; ++k) fn("false_by_height", HeightBins::name(k), b.falseByHeight[std::size_t(k)]);
    for (int k = 0; k < RangeBins::kCount; ++k) fn("false_by_range", RangeBins::name(k), b.falseByRange[std::size_t(k)]);
    for (const auto& [id, n] : b.missedByClass) fn("missed_by_class", semanticClassName(id), n);
    for (int k = 0; k < RangeBins::kCount; ++k) fn("missed_by_range", RangeBins::name(k), b.missedByRange[std::size_t(k)]);
}

std::string breakdownRows(const std::string& seq, const std::string& frame, const Breakdown& b) {
    std::string o;
    forEachBin(b, [&](const char* kind, const std::string& bin, std::uint64_t n) {
        o += format("%s,%s,%s,%s,%llu\n", seq.c_str(), frame.c_str(), kind, bin.c_str(), ull(n));
    });
    return o;
}

std::string shareTable(const char* title, std::uint64_t total,
                       const std::vector<std::pair<std::string, std::uint64_t>>& rows) {
    std::string o = format("  %s (%llu points):\n", title, ull(total));
    for (const auto& [name, n] : rows)
        if (n > 0)
            o += format("    %-22s %9llu  %5.1f %%\n", name.c_str(), ull(n), total ? 100.0 * double(n) / double(total) : 0.0);
    return o;
}

std::string describe(const std::string& title, const Breakdown& b) {
    std::vector<std::pair<std::string, std::uint64_t>> fc, fh, fr, mc, mr;
    for (const auto& [id, n] : b.falseByClass) fc.emplace_back(semanticClassName(id), n);
    for (const auto& [id, n] : b.missedByClass) mc.emplace_back(semanticClassName(id), n);
    auto byCount = [](const auto& a, const auto& c) { return a.second > c.second; };
    std::stable_sort(fc.begin(), fc.end(), byCount);
    std::stable_sort(mc.begin(), mc.end(), byCount);
    for (int k = 0; k < HeightBins::kCount; ++k) fh.emplace_back(HeightBins::name(k), b.falseByHeight[std::size_t(k)]);
    for (int k = 0; k < RangeBins::kCount; ++k) {
        fr.emplace_back(RangeBins::name(k), b.falseByRange[std::size_t(k)]);
        mr.emplace_back(RangeBins::name(k), b.missedByRange[std::size_t(k)]);
    }
    return title + "\n" + shareTable("false ground by class", b.falseGround, fc) +
           shareTable("false ground by height above the local labelled ground", b.falseGround, fh) +
           shareTable("false ground by range", b.falseGround, fr) +
           shareTable("missed ground by class", b.missedGround, mc) +
           shareTable("missed ground by range", b.missedGround, mr);
}

Breakdown total(const std::vector<SequenceSummary>& seqs) {
    Breakdown all;
    for (const SequenceSummary& s : seqs) all += s.breakdown;
    return all;
}

}  // namespace

std::string breakdownCsv(const std::vector<FrameRow>& frames, const std::vector<SequenceSummary>& seqs) {
    std::string o = "sequence,frame,kind,bin,points\n";
    for (const FrameRow& f : frames) o += breakdownRows(f.sequence, f.name, f.breakdown);
    for (const SequenceSummary& s : seqs) o += breakdownRows(s.sequence, "all", s.breakdown);
    return o + breakdownRows("all", "all", total(seqs));
}

std::string breakdownText(const std::vector<SequenceSummary>& seqs) {
    std::string o;
    if (seqs.size() > 1)
        for (const SequenceSummary& s : seqs) o += describe("failure breakdown, sequence " + s.sequence + ":", s.breakdown);
    return o + describe("failure breakdown, all frames:", total(seqs));
}

}  // namespace gseg::app
