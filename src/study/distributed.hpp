// The sweep's points over MPI ranks (distributed.cpp): rank 0 hands out points on request and
// gathers the rows; the others evaluate what they are given.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "trochomill/progress.hpp"
#include "trochomill/study.hpp"

namespace trochomill::detail {

/// Rank 0: hands out `todo` (positions 0..n-1) to the other ranks and to a local thread,
/// calling `row_done(position, line)` (serialised) as rows arrive. Other ranks: evaluate the
/// points they are given with `row_of(point)` until told to stop. Cancelling stops handing
/// out; the rows in flight still arrive.
void distribute_points(const Distributed& world, const std::vector<std::size_t>& todo,
                       const std::function<std::string(std::size_t)>& row_of,
                       const std::function<void(std::size_t, std::string)>& row_done,
                       const RunHooks& hooks);

/// Rank 0 tells the others whether the run goes ahead (`go`: it prepared the file); each
/// rank returns the answer. One rank: `go`.
bool agree_to_start(const Distributed& world, bool go);

}  // namespace trochomill::detail
