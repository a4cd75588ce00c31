#pragma once
// The process's peak resident memory, for profiles (convert's stages, the
// benches). Linux: VmHWM in /proc/self/status, restarted at the current
// resident size through /proc/self/clear_refs (Linux >= 4.0). Process-wide:
// with several jobs at once in one process each sees the others' memory.
namespace isowave {

// Peak resident bytes since the start or the last reset_peak_memory(); 0
// where the system does not say. O(1) (reads a small /proc file).
double peak_memory_bytes();

// Restarts the peak at the current resident size; nothing where the system
// does not allow it.
void reset_peak_memory();

}  // namespace isowave
