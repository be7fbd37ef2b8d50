// What the ranks agree on, in terms of gather and broadcast (the same with and without MPI).
#include "ranks.hpp"

#include <gseg/io/bytes.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <sched.h>
#include <unistd.h>

namespace gseg::tools {

using io::ByteReader;
using io::ByteWriter;

std::string Ranks::firstError(const std::string& mine) {
    std::string first;
    const std::vector<std::string> all = gather(mine);
    for (std::size_t r = 0; r < all.size() && first.empty(); ++r)
        if (!all[r].empty()) first = (r ? "rank " + std::to_string(r) + ": " : std::string()) + all[r];
    return broadcast(first);
}

int Ranks::exitCode(int mine) {
    int code = 0;
    for (const std::string& c : gather(std::to_string(mine)))
        if (code == 0) code = std::stoi(c);
    return std::stoi(broadcast(std::to_string(code)));
}

namespace {

std::vector<int> threadCpus() {
    std::vector<int> cpus;
    cpu_set_t set;
    CPU_ZERO(&set);
    if (::sched_getaffinity(0, sizeof set, &set) == 0)
        for (int c = 0; c < CPU_SETSIZE; ++c)
            if (CPU_ISSET(c, &set)) cpus.push_back(c);
    return cpus;
}

}  // namespace

std::vector<int> cpusOfRanksOnThisMachine(Ranks& ranks) {
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
    std::string mine = host;
    for (int c : threadCpus()) mine += " " + std::to_string(c);
    const std::vector<std::string> all = ranks.gather(mine);
    std::vector<int> cpus;
    if (all.empty()) return cpus;
    std::string rootHost;
    std::istringstream(all[0]) >> rootHost;
    for (const std::string& r : all) {
        std::istringstream in(r);
        std::string h;
        in >> h;
        if (h != rootHost) continue;
        for (int c; in >> c;) cpus.push_back(c);
    }
    std::sort(cpus.begin(), cpus.end());
    cpus.erase(std::unique(cpus.begin(), cpus.end()), cpus.end());
    return cpus;
}

WiderAffinity::WiderAffinity(const std::vector<int>& cpus) {
    cpu_set_t own, wide;
    CPU_ZERO(&own);
    if (::sched_getaffinity(0, sizeof own, &own) != 0) return;
    count_ = unsigned(std::max(1, CPU_COUNT(&own)));
    wide = own;
    for (int c : cpus)
        if (c >= 0 && c < CPU_SETSIZE) CPU_SET(c, &wide);
    if (CPU_EQUAL(&wide, &own) || ::sched_setaffinity(0, sizeof wide, &wide) != 0) return;
    own_.resize(sizeof own);
    std::memcpy(own_.data(), &own, sizeof own);
    count_ = unsigned(CPU_COUNT(&wide));
}

WiderAffinity::~WiderAffinity() {
    if (own_.empty()) return;
    cpu_set_t own;
    std::memcpy(&own, own_.data(), sizeof own);
    ::sched_setaffinity(0, sizeof own, &own);
}

std::vector<std::string> shareItems(Ranks& ranks, const std::vector<std::uint64_t>& work,
                                    const std::function<std::vector<std::string>(const std::vector<std::size_t>&)>& doMine,
                                    std::vector<int>* owner) {
    const std::vector<int> split = splitByWork(work, ranks.size());
    if (owner) *owner = split;
    std::vector<std::size_t> mine;
    for (std::size_t i = 0; i < split.size(); ++i)
        if (split[i] == ranks.rank()) mine.push_back(i);
    ByteWriter out;
    std::string error;
    try {
        const std::vector<std::string> done = doMine(mine);
        if (done.size() != mine.size()) throw std::logic_error("shareItems: one result per item expected");
        for (std::size_t k = 0; k < mine.size(); ++k) out.u64(mine[k]).str(done[k]);
    } catch (const std::exception& e) {
        error = e.what();
    }
    if (const std::string first = ranks.firstError(error); !first.empty()) throw std::runtime_error(first);
    std::vector<std::string> all(ranks.root() ? split.size() : 0);
    for (const std::string& part : ranks.gather(out.bytes())) {
        ByteReader in(part);
        while (!in.done()) {
            const std::uint64_t i = in.u64();
            all.at(std::size_t(i)) = in.str();
        }
    }
    return all;
}

std::vector<std::uint64_t> fileSizes(const std::vector<std::string>& paths) {
    std::vector<std::uint64_t> sizes;
    for (const std::string& p : paths) {
        std::error_code ec;
        const std::uintmax_t n = std::filesystem::file_size(p, ec);
        sizes.push_back(ec ? 0 : std::uint64_t(n));
    }
    return sizes;
}

std::vector<int> splitByWork(const std::vector<std::uint64_t>& work, int ranks) {
    if (ranks < 1) throw std::invalid_argument("splitByWork: needs at least one rank");
    std::vector<std::size_t> order(work.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return work[a] > work[b]; });
    std::vector<std::pair<std::uint64_t, std::size_t>> load(static_cast<std::size_t>(ranks));  // work, items
    std::vector<int> owner(work.size(), 0);
    for (const std::size_t i : order) {
        const auto least = std::min_element(load.begin(), load.end());  // the first of equals: the lowest rank
        owner[i] = int(least - load.begin());
        least->first += work[i], ++least->second;
    }
    return owner;
}

}  // namespace gseg::tools
