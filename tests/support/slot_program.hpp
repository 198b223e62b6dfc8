#pragma once
// A job program as cncstream writes one, small enough to read: its stock and
// operation comments, a tool change with its M0 at line 16.
namespace testparts {

// A 6 mm flat slot 10 mm long, 2 mm deep, in a 30 x 20 x 5 block; then a
// tool change to a 2 mm ball that cuts nothing more (it stays above).
inline constexpr const char* kSlotProgram =
    "(cncstream job: a slot)\n"
    "(stock: X 0.000..30.000 Y 0.000..20.000 Z -5.000..0.000 [work coordinates])\n"
    "G21 G90 G17 G94\n"
    "(operation 1: slot with T1, 6 mm flat end mill [flat:6])\n"
    "T1\n"
    "M3 S18000\n"
    "G0 Z5\n"
    "X10 Y10\n"
    "G1 Z-2 F300\n"
    "X20 F600\n"
    "G0 Z5\n"
    "(operation 2: nothing with T2, 2 mm ball-nose end mill [ball:2])\n"
    "M5\n"
    "(TOOL CHANGE: mount T2)\n"
    "T2\n"
    "M0\n"
    "M3 S18000\n"
    "G0 X5 Y5\n"
    "M2\n";

}  // namespace testparts
