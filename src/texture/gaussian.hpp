// The ISO 16610-21 Gaussian weighting function, shared by the profile and the areal filters
// (profile.cpp, areal.cpp); internal to the texture module.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace trochomill::detail {

/// Kernel samples each side of the centre the filter may use (400 MB of weights).
inline constexpr double kMaxKernelHalf = 2.5e7;

/// floor(cutoff / dx): the samples each side within +-cutoff. Throws InputError past
/// kMaxKernelHalf (before anything is allocated).
std::size_t kernel_half(double dx_mm, double cutoff_mm);

/// The weighting function s(x) = exp(-pi (x / (alpha lambda_c))^2) on the samples within
/// +-cutoff, at most `reach` each side (a line shorter than the kernel never weights the
/// samples beyond it), normalised to sum to one.
std::vector<double> gaussian_weights(double dx_mm, double cutoff_mm,
                                     std::size_t reach = std::numeric_limits<std::size_t>::max());

}  // namespace trochomill::detail
