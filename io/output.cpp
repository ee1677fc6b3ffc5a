#include "io/output.hpp"

#include "core/errors.hpp"
#include "io/hdf5_writer.hpp"
#include "io/json_writer.hpp"

#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

namespace vproxq {

namespace {

namespace fs = std::filesystem;

// ---- Cleanup on a fatal signal ---------------------------------------------------------
//
// A run stopped by SIGINT, SIGTERM or SIGHUP (Ctrl-C, timeout, a closed terminal), ended by a
// crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT), or by any other signal whose default action
// ends the process (SIGQUIT, SIGXCPU from a CPU-time limit, SIGALRM, SIGUSR1, ..., the real-time
// signals), would otherwise leave its temporary files and the directories it created. SIGXFSZ (a
// write past the file-size limit, `ulimit -f`) is ignored instead: the write then fails with
// EFBIG and the run ends as for any failed write, with a message naming the file. The paths live
// in fixed slots that the handler reads with async-signal-safe calls only (unlink, rmdir,
// signal, raise): files first, then directories, newest first; then the signal is raised again
// with its default action, so the exit status (and a core dump, where enabled) still says which
// signal ended the run. The handler runs on its own stack, so that a stack overflow still
// reaches it (this one for the main thread; the pool threads of core/parallel.hpp set up their
// own). What no handler sees (SIGKILL, as from the out-of-memory killer) is cleaned up by the
// next run into the same directory: remove_stale_temporaries().
constexpr int kCleanupSlots = 16;
constexpr std::size_t kCleanupPathMax = 4096;
struct CleanupSlot {
  std::atomic<int> kind{0};  ///< 0 free, 1 file, 2 directory
  char path[kCleanupPathMax];
};
CleanupSlot g_cleanup[kCleanupSlots];

extern "C" void remove_partial_output(int sig) {
  for (int kind : {1, 2})
    for (int k = kCleanupSlots - 1; k >= 0; --k)
      if (g_cleanup[k].kind.load() == kind) kind == 1 ? ::unlink(g_cleanup[k].path) : ::rmdir(g_cleanup[k].path);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

/// Installs remove_partial_output() for the signals whose action is still the default (a
/// signal the caller ignores stays ignored).
void install_cleanup_handlers() {
  static const bool installed = [] {
    static char alternate_stack[1 << 16];
    stack_t ss{};
    ss.ss_sp = alternate_stack;
    ss.ss_size = sizeof alternate_stack;
    const bool on_stack = ::sigaltstack(&ss, nullptr) == 0;
    auto at_default = [](int sig) {
      struct sigaction old {};
      return ::sigaction(sig, nullptr, &old) == 0 && !(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_DFL;
    };
    auto handle = [&](int sig) {
      if (!at_default(sig)) return;
      struct sigaction act {};
      act.sa_handler = remove_partial_output;
      act.sa_flags = on_stack ? SA_ONSTACK : 0;
      sigemptyset(&act.sa_mask);
      ::sigaction(sig, &act, nullptr);
    };
    // The signals whose default action ends the process, but SIGKILL and SIGSTOP (they cannot
    // be caught), SIGPIPE (app/cli.cpp decides) and SIGXFSZ (below).
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGQUIT, SIGTRAP, SIGSYS,
                    SIGXCPU, SIGALRM, SIGVTALRM, SIGPROF, SIGUSR1, SIGUSR2, SIGIO, SIGPWR, SIGSTKFLT})
      handle(sig);
    for (int sig = SIGRTMIN; sig <= SIGRTMAX; ++sig) handle(sig);
    if (at_default(SIGXFSZ)) std::signal(SIGXFSZ, SIG_IGN);
    return true;
  }();
  (void)installed;
}

/// Registers `path` for removal on a fatal signal; returns its slot, or -1 when none is free
/// or the path is too long (then only the normal cleanup applies).
int register_cleanup(const fs::path& path, int kind) {
  const std::string& s = path.native();
  if (s.size() + 1 > kCleanupPathMax) return -1;
  for (int k = 0; k < kCleanupSlots; ++k) {
    if (g_cleanup[k].kind.load() != 0) continue;
    std::memcpy(g_cleanup[k].path, s.c_str(), s.size() + 1);
    g_cleanup[k].kind.store(kind);
    return k;
  }
  return -1;
}

void unregister_cleanup(int& slot) {
  if (slot >= 0) g_cleanup[slot].kind.store(0);
  slot = -1;
}

/// A temporary file name that is removed on destruction unless it was moved into place.
class TempPath {
 public:
  /// `on_signal`: also remove the file when a fatal signal ends the run.
  explicit TempPath(fs::path path, bool on_signal = true)
      : path_(std::move(path)), slot_(on_signal ? register_cleanup(path_, 1) : -1) {}
  ~TempPath() {
    unregister_cleanup(slot_);
    if (!path_.empty()) {
      std::error_code ignored;
      fs::remove(path_, ignored);
    }
  }
  TempPath(const TempPath&) = delete;
  TempPath& operator=(const TempPath&) = delete;

  const fs::path& path() const { return path_; }

  /// Atomically replaces `target` with this file (rename(2)); afterwards nothing is removed.
  void move_to(const fs::path& target) {
    std::error_code ec;
    fs::rename(path_, target, ec);
    if (ec) {
      throw RuntimeError("cannot rename '" + path_.string() + "' to '" + target.string() +
                         "': " + ec.message());
    }
    unregister_cleanup(slot_);
    path_.clear();
  }

  /// Forgets the path: nothing is removed on destruction.
  void release() {
    unregister_cleanup(slot_);
    path_.clear();
  }

 private:
  fs::path path_;
  int slot_ = -1;
};

/// This machine's name, reduced to [A-Za-z0-9.-] (it goes into file names).
const std::string& host_tag() {
  static const std::string tag = [] {
    char name[256] = {};
    if (::gethostname(name, sizeof name - 1) != 0) name[0] = '\0';
    std::string t;
    for (const char* c = name; *c != '\0'; ++c)
      if (std::isalnum(static_cast<unsigned char>(*c)) || *c == '.' || *c == '-') t += *c;
    return t.empty() ? std::string("host") : t;
  }();
  return tag;
}

constexpr const char* kJsonName = "results.json";
constexpr const char* kHdf5Name = "results.h5";

/// `.NAME.tmp-HOST-`, the part of a temporary's name before the process id.
std::string temp_prefix(const char* final_name) {
  return "." + std::string(final_name) + ".tmp-" + host_tag() + "-";
}

/// `.NAME.tmp-HOST-PID`: the host and the process, so that a later run can tell a temporary
/// left by a process that no longer exists (remove_stale_temporaries()).
fs::path temp_name(const fs::path& dir, const char* final_name) {
  return dir / (temp_prefix(final_name) + std::to_string(::getpid()));
}

/// Removes `.results.json.tmp-HOST-PID` and `.results.h5.tmp-HOST-PID` files in `dir` that a
/// run on this host left when it was killed without a chance to clean up (SIGKILL, power
/// loss): the host is this one and no process PID exists. Temporaries of live runs, of other
/// hosts (a shared file system) and anything else are left alone; so is an earlier
/// results.h5 moved aside during a commit (`.results.h5.previous.tmp-*`), which may be the
/// only copy of earlier results.
void remove_stale_temporaries(const fs::path& dir) {
  std::error_code ec;
  fs::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    for (const char* final_name : {kJsonName, kHdf5Name}) {
      const std::string prefix = temp_prefix(final_name);
      if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string digits = name.substr(prefix.size());
      if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
      const long pid = std::stol(digits);
      if (pid <= 0 || pid == ::getpid()) continue;
      if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or unknown
      std::error_code ignored;
      if (fs::is_regular_file(fs::symlink_status(it->path(), ignored))) fs::remove(it->path(), ignored);
    }
  }
}

/// The directories that prepare_dir() created for a run (deepest last), removed again when
/// the run does not commit, so that a failed run leaves no trace of itself.
class CreatedDirs {
 public:
  CreatedDirs() = default;
  CreatedDirs(const CreatedDirs&) = delete;
  CreatedDirs& operator=(const CreatedDirs&) = delete;
  ~CreatedDirs() {
    // fs::remove() removes only empty directories: one that something else has written into
    // since stays, with what is in it.
    std::error_code ignored;
    for (auto it = dirs_.rbegin(); it != dirs_.rend(); ++it) fs::remove(*it, ignored);
    keep();
  }
  void add(fs::path dir) {
    slots_.push_back(register_cleanup(dir, 2));
    dirs_.push_back(std::move(dir));
  }
  void keep() {
    for (int& slot : slots_) unregister_cleanup(slot);
    slots_.clear();
    dirs_.clear();
  }

 private:
  std::vector<fs::path> dirs_;
  std::vector<int> slots_;
};

/// Creates `out_dir` and its missing parents, recording the ones it created in `created`.
fs::path prepare_dir(const fs::path& out_dir, CreatedDirs& created) {
  std::error_code ec;
  std::vector<fs::path> missing;
  for (fs::path p = out_dir; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (fs::create_directory(*it, ec)) created.add(*it);
    if (ec) {
      throw RuntimeError("cannot create output directory '" + out_dir.string() +
                         "': " + ec.message());
    }
  }
  if (!fs::is_directory(out_dir, ec)) {
    throw RuntimeError("output path '" + out_dir.string() + "' is not a directory");
  }
  remove_stale_temporaries(out_dir);
  return out_dir;
}

/// One run at a time per output directory: two runs into the same `OUT` would each rename
/// their results.h5 and results.json into place, and could leave one run's JSON beside the
/// other's HDF5. The lock is flock(2) on the directory itself (no lock file to leave behind);
/// the system releases it when the process ends, however it ends (SIGKILL included). Where
/// the file system cannot lock (some network file systems), runs go unlocked, as before.
class DirLock {
 public:
  explicit DirLock(const fs::path& dir) : fd_(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_ < 0) return;
    if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      throw RuntimeError("output directory '" + dir.string() +
                         "' is in use by another vproxq run (their results would be mixed); wait for it to "
                         "end or choose another -o");
    }
  }
  ~DirLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  DirLock(const DirLock&) = delete;
  DirLock& operator=(const DirLock&) = delete;

 private:
  int fd_;
};

// Flushes a closed file's data to disk, so that a rename never exposes an incomplete file
// after a crash.
void sync_file(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY);
  if (fd < 0 || ::fsync(fd) != 0) {
    const int error = errno;
    if (fd >= 0) ::close(fd);
    throw RuntimeError("cannot sync '" + file.string() + "': " + std::strerror(error));
  }
  ::close(fd);
}

}  // namespace

// Members are declared so that, whatever throws, the open files are closed before their
// temporaries are removed (members are destroyed in reverse order).
struct ResultWriter::Impl {
  explicit Impl(const fs::path& out_dir, const RunInfo& info)
      : dir(prepare_dir(out_dir, created_dirs)),
        lock(dir),
        json_temp(temp_name(dir, kJsonName)),
        h5_temp(temp_name(dir, kHdf5Name)),
        json(std::in_place, json_temp.path(), info),
        h5(std::in_place, h5_temp.path(), info) {}

  CreatedDirs created_dirs;  // first: destroyed after the temporaries are removed
  fs::path dir;
  DirLock lock;  // taken before the temporaries exist, released after they are gone
  TempPath json_temp;
  TempPath h5_temp;
  std::optional<detail::JsonResultStream> json;
  std::optional<detail::Hdf5ResultWriter> h5;
  bool failed = false;     ///< a write threw: the files may be inconsistent, never commit them
  bool committed = false;
};

ResultWriter::ResultWriter(const fs::path& out_dir, const RunInfo& info)
    : impl_((install_cleanup_handlers(), std::make_unique<Impl>(out_dir, info))) {}

double ResultWriter::write_frame(const FrameResult& frame) {
  Impl& m = *impl_;
  if (m.committed) throw RuntimeError("results in '" + m.dir.string() + "' already committed");
  if (m.failed) throw RuntimeError("an earlier write to '" + m.dir.string() + "' failed");
  try {
    const auto started = std::chrono::steady_clock::now();
    const double write_ms = m.h5->write_frame(frame, started);
    m.json->write_frame(frame, write_ms);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
        .count();
  } catch (...) {
    m.failed = true;
    throw;
  }
}

void ResultWriter::commit() {
  Impl& m = *impl_;
  if (m.committed) throw RuntimeError("results in '" + m.dir.string() + "' already committed");
  if (m.failed) throw RuntimeError("an earlier write to '" + m.dir.string() + "' failed");
  m.failed = true;  // until every step below has succeeded
  m.json->close();
  m.h5->close();
  sync_file(m.h5_temp.path());
  const fs::path h5_final = m.dir / kHdf5Name, json_final = m.dir / kJsonName;
  for (const fs::path& target : {h5_final, json_final}) {
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(target, ec);
    if (fs::exists(st) && !fs::is_regular_file(st)) {
      throw RuntimeError("cannot write '" + target.string() + "': it exists and is not a regular file");
    }
  }
  // results.json last: its presence means that results.h5 of the same run is in place too.
  // An earlier results.h5 is moved aside first and put back should results.json fail to
  // move into place (or results.h5 itself fails to), so that a failed commit leaves the
  // earlier pair as it was.
  // (Not removed on a signal: a run stopped right here leaves the earlier file under this
  // name rather than losing it.)
  TempPath previous_h5(temp_name(m.dir, "results.h5.previous"), false);
  std::error_code ec;
  fs::rename(h5_final, previous_h5.path(), ec);
  const bool had_previous = !ec;
  if (!had_previous) previous_h5.release();  // nothing there to remove
  try {
    m.h5_temp.move_to(h5_final);
    m.json_temp.move_to(json_final);
  } catch (const RuntimeError& e) {
    std::string kept;
    std::error_code restore;
    if (had_previous) {
      const fs::path aside = previous_h5.path();
      fs::rename(aside, h5_final, restore);
      previous_h5.release();  // restored, or left where it is rather than lost
      if (restore) kept = "; the earlier results.h5 is left as '" + aside.string() + "'";
    } else {
      fs::remove(h5_final, restore);
    }
    throw RuntimeError(e.what() + kept);
  }
  m.failed = false;
  m.committed = true;
  m.created_dirs.keep();
}

ResultWriter::~ResultWriter() = default;

}  // namespace vproxq
