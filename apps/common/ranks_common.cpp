// What the ranks agree on, in terms of gather and broadcast (the same with and without MPI).
#include "ranks.hpp"

#include <algorithm>
#include <numeric>
#include <utility>
#include <stdexcept>

namespace gseg::tools {

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
