#pragma once
// Where the GL grid may differ from the exact one by more than the
// tessellation bound: nodes beside a vertical part of the exact CL surface
// (a cap's rim, a wall), which the rasterizer's vertex snapping or the gap
// between an inscribed polygon and the true rim puts on the other side. The
// tests and tools/compare_gl_cl.cpp tell such nodes from errors by looking
// around them on the exact surface.
#include "cncstream/cam/cl_engine.hpp"

namespace cncstream::gl {

// The highest (or lowest) exact CL height on 32 points of a circle of radius
// r around (x, y); the lowest is -inf where a point of the circle touches
// nothing (any height is consistent there).
double exact_height_around(const cam::ClEngine& exact, double x, double y, double r, bool highest);

}  // namespace cncstream::gl
