// Ranks without MPI (GSEG_WITH_MPI off): this process alone.
#include "ranks.hpp"

#include <stdexcept>

namespace gseg::tools {

class Ranks::Watch {};

Ranks::Ranks(int&, char**&) {}
Ranks::~Ranks() = default;
void Ranks::setTimeout(const std::string&, double) {}
bool Ranks::built() { return false; }

void Ranks::send(int, int, const std::string&) { throw std::logic_error("Ranks::send: there is no other process"); }
std::string Ranks::receive(int, int) { throw std::logic_error("Ranks::receive: there is no other process"); }
std::vector<std::string> Ranks::gather(const std::string& mine) { return {mine}; }
std::string Ranks::broadcast(const std::string& value) { return value; }

}  // namespace gseg::tools
