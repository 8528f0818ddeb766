#pragma once
// Background work (a global BA) that must not take the cores from tracking and local mapping when a machine
// has fewer cores than the pipeline has threads.

namespace semslam {

// Lowers the calling thread's scheduling priority by `steps` (Linux: its nice value, at most 19). Returns false
// where the platform or the process's limits do not allow it; the thread then runs as before.
bool LowerCurrentThreadPriority(int steps);

// The calling thread's nice value (0 where unknown).
int CurrentThreadNiceValue();

}  // namespace semslam
