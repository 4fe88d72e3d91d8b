#pragma once
// The standard streams of a tool's process. stderr carries diagnostics (errors, warnings,
// progress): losing one (stream closed, full, a pipe nobody reads) loses that line and nothing
// else. stdout carries the report, the tool's product: losing it is a failure to write output.

#include <cstdio>
#include <string_view>

namespace svokit {

/// Run first in main. Puts /dev/null, opened read-only, on each closed standard descriptor, so
/// that no file the process opens takes number 1 or 2 (a report would be written into an output)
/// and writes to it still fail with EBADF, as on the closed one. Ignores SIGPIPE and SIGXFSZ, so
/// that a pipe nobody reads (EPIPE) and a file-size limit (EFBIG) fail the write instead of
/// killing the process without a word; both stay ignored in programs it executes. Buffers stdout
/// fully (1 MiB), so that a report is written at FlushReport.
void GuardStandardStreams();

/// Writes `text` to `out` and flushes it, ignoring any failure: never throws, never aborts.
void WriteDiagnostic(std::string_view text, std::FILE* out = stderr) noexcept;

/// Flushes the report (stdout, and std::cout over it) and returns the errno of a write of it that
/// failed since the process started, or 0 when all of it was written.
int FlushReport() noexcept;

}  // namespace svokit
