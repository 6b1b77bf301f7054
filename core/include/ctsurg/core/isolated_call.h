// A library call that may crash, run in a child process. GDCM, which ctsurg uses to read DICOM,
// asserts on damaged files (Debian builds it with assertions: "Should not happen" aborts found by
// tests/fuzz/fuzz_dicom_folder.cpp) and allocates what a header declares; no check before it can foresee
// every such path. In a forked child a crash becomes a clear refusal of the input instead of the
// tool's death.
//
// The child runs `work`; what it returns (bytes) comes back to the parent through an unnamed
// temporary file, an InputError or RuntimeError it throws is thrown again in the parent with the
// same file, field and problem, and what the child prints on stderr is captured. The child
// reports progress by calling progress(done, total); the parent calls on_progress with the same
// numbers, so a progress bar can live in the parent, whose stderr is the terminal. Only for
// single-threaded moments of a tool (fork copies one thread), as ctsurg-import's reading is.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace ctsurg {

// Runs work(progress) in a child process and returns its bytes. InputError(input, "", ...) when the
// child dies of a signal (naming it, with what the libraries printed) or, with timeout_s > 0, is still
// running after timeout_s seconds (it is killed); RuntimeError when it cannot be started.
using ProgressReport = std::function<void(uint64_t done, uint64_t total)>;
std::string isolated_call(const std::string& input, const std::function<std::string(const ProgressReport& progress)>& work,
                          const ProgressReport& on_progress = {}, double timeout_s = 0);

}  // namespace ctsurg
