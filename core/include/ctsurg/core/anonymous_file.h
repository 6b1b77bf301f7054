// An unnamed temporary file: a read-write descriptor of a file that has no name (O_TMPFILE where
// the file system has it, else a file unlinked as soon as it is made), in $TMPDIR or /tmp, gone when
// the last descriptor closes. For text a library prints and results a child process hands back.
#pragma once

namespace ctsurg {

// The descriptor (close-on-exec), or -1 when no file can be made.
int anonymous_file();

}  // namespace ctsurg
