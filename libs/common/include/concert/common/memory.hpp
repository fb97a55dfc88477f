#pragma once
// glibc's heap in a long-running service.

namespace concert {

/// Fixes glibc's mmap threshold at its default, 128 KiB: a block at least that large is mapped on
/// its own and returned to the system when freed. Left alone, glibc raises the threshold to the
/// size of each mapped block freed (up to 32 MiB), and later blocks of that size come from the
/// heap, which fragments and seldom shrinks. A hot swap frees and makes the simulator's and the
/// planner's model buffers: concert_robot over 23 hot swaps grew from 209 to 259 MB resident with
/// the moving threshold, from 173 to 177 MB with it fixed. Call first thing in main; false when
/// glibc refused.
bool fix_malloc_thresholds();

}  // namespace concert
