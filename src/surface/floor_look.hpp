// The floor's first look at its points (src/surface/floor.cpp), for tests.
#pragma once

#include <atomic>

namespace trochomill::detail {

/// Whether floor_profile takes its first look at a range of points four at a time with AVX2
/// (true at start where the processor has AVX2, and only there; set true elsewhere it changes
/// nothing: floor_profile asks the processor too). A test switches it off to compare the floor
/// with the one of the look point by point: they must be the same doubles.
std::atomic<bool>& floor_vector_look();

}  // namespace trochomill::detail
