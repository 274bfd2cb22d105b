// Stand-in for Boost's array header when Boost is not installed: laser_line_extraction uses
// boost::array only as a fixed-size array, which std::array is.
#pragma once
#include <array>
namespace boost {
template <class T, std::size_t N>
using array = std::array<T, N>;
}
