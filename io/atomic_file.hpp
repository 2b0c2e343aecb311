// Outputs are written whole or not at all: the content goes to a temporary file in the same
// directory, which is renamed over the target only after it was written and flushed to the disk
// (fsync: after a power loss the target is the old file or the new one, never an empty one; the
// rename itself may be lost, a staged output's directory is flushed after its renames). The
// temporary is hidden, `.NAME.jpcr-tmp.PID.N`; one left by a process that was killed outright
// (SIGKILL) is removed by the next write into that directory once the PID no longer exists.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace jpcr {

/// Calls write(stream) on a temporary file next to `path`, then renames it to `path`. If write
/// throws or the stream fails, the temporary file is removed and `path` is left untouched.
/// Throws InputError naming the file when it cannot be written, and before writing anything
/// when output_file_target refuses `path`. The first call for a directory in a process removes
/// the temporaries there of processes that no longer exist.
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write);

/// The file a whole-file write to `path` replaces: `path` itself when nothing is there or a
/// regular file is; the regular file a symbolic link leads to (the link stays). Throws
/// InputError naming `path` for anything else: a device, a pipe, a socket or a directory (a
/// rename would replace it: `--out /dev/null` as root deleted the device node), a link that
/// leads nowhere or in a loop. For the checks before a run and for write_file_atomically.
std::string output_file_target(const std::string& path);

/// Whether `pid` names no process (kill(pid, 0) fails with ESRCH): what a process of that PID
/// left behind is abandoned. A live PID, this process's and one this process may not signal are
/// not gone. PIDs are this host's: a file system shared with another host running the same
/// program can see its live PIDs as gone.
bool process_is_gone(long pid);

/// The PID `name` ends with after `prefix` ("traj.txt.partial-" and "1234"), or 0 when the rest
/// is not 1 to 9 digits: how a run names the copies and staging directories it owns.
long owner_pid(const std::string& name, const std::string& prefix);

/// Flushes a directory's entries (renames into it) to the disk; best effort, errors ignored.
void sync_directory(const std::string& dir);

/// Creates `dir` and its parents when missing; throws InputError naming it on failure.
void ensure_directory(const std::string& dir);
/// ensure_directory of the directory `file` lies in (none for a bare file name).
void ensure_parent_directory(const std::string& file);

/// Reads a whole regular file into memory; throws InputError naming it when it cannot be read
/// or is not a regular file (a FIFO, a device).
std::string read_file(const std::string& path);

}  // namespace jpcr
