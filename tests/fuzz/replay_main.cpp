// Runs a fuzz harness without libFuzzer, with any compiler: linked with one harness's
// LLVMFuzzerTestOneInput (and its LLVMFuzzerInitialize, where it has one), it feeds it the seed
// files named on the command line, then a fixed sequence of inputs generated from --seed:
// random bytes (the harnesses that decode bytes into numbers) and mutants of the seeds (bits
// flipped, characters and number-like tokens inserted, numbers replaced, bytes deleted, the end
// cut, lines duplicated, deleted or swapped, two seeds spliced). Generated input i depends only
// on the seeds, --seed, --max-len, --join and i, so a run is the same on every machine; ctest
// runs every harness this way (FuzzReplay.*, tests/fuzz/CMakeLists.txt).
//
// A failed check traps (VPROXQ_FUZZ_CHECK, trap_on_test_failure.cpp), as does any crash: a
// handler then writes the input that was running to the crash file (an input for the libFuzzer
// harness, or a seed for this program), says which input it was, and lets the signal kill the
// process.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "support/rng.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
// Weak: most harnesses have none (the pointer is then null).
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) __attribute__((weak));

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

constexpr const char* kUsage =
    "usage: %s [options] [FILE|DIR ...]\n"
    "Runs the fuzz harness on the seed files (directories recursively, in name order), then on\n"
    "--runs inputs generated from --seed: mutants of the seeds, and random bytes.\n"
    "  --runs N           generated inputs (default 1000)\n"
    "  --seed S           the generator's seed (default 1)\n"
    "  --max-len L        random inputs have 0 to L bytes (default 256)\n"
    "  --max-seconds T    generate no more inputs after T seconds (the seeds always run)\n"
    "  --join XX          an input is two files joined by the byte 0xXX (fuzz_result_diff: ff):\n"
    "                     the seeds run in every pair, the mutants come in pairs\n"
    "  --only I           run generated input I alone (the seeds are read, not run)\n"
    "  --crash-file F     where the input goes when one fails (default: PROGRAM-crash.bin)\n"
    "  --max-seed-size B  skip seed files over B bytes (default 1048576)\n"
    "VPROXQ_REPLAY_VERBOSE=1 prints each input before it runs.\n";

// ---- The input that is running, for the fatal-signal handler ----------------------------------

struct Running {
  const std::uint8_t* data = nullptr;  // null between inputs
  std::size_t size = 0;
  std::uint64_t index = 0;             // among all inputs run
  std::int64_t generated = -1;         // generated input number, or -1 for a seed
  const char* seed_file = "";          // a seed's file
  const char* joined_file = nullptr;   // with --join, the pair's second file
  std::uint64_t seed = 0;
  const char* crash_file = "";
};
Running g_running;

// Only async-signal-safe calls below (write, open, close, raise).
void say(const char* s) {
  std::size_t n = std::strlen(s);
  while (n > 0) {
    const ssize_t w = write(STDERR_FILENO, s, n);
    if (w <= 0) return;
    s += w;
    n -= static_cast<std::size_t>(w);
  }
}

void say_number(std::uint64_t v) {
  char buf[24];
  char* p = buf + sizeof buf;
  *--p = '\0';
  do {
    *--p = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0);
  say(p);
}

extern "C" void on_fatal_signal(int sig) {
  say("\nreplay: signal ");
  say_number(static_cast<std::uint64_t>(sig));
  if (g_running.data == nullptr) {
    say(" outside the inputs (in LLVMFuzzerInitialize or at exit)\n");
    raise(sig);
    return;
  }
  say(" during input ");
  say_number(g_running.index);
  if (g_running.generated >= 0) {
    say(" (generated input ");
    say_number(static_cast<std::uint64_t>(g_running.generated));
    say(" of --seed ");
    say_number(g_running.seed);
    say(": rerun with --only ");
    say_number(static_cast<std::uint64_t>(g_running.generated));
    say(" and the same seeds and options)");
  } else {
    say(" (seed file ");
    say(g_running.seed_file);
    if (g_running.joined_file != nullptr) {
      say(" joined with ");
      say(g_running.joined_file);
    }
    say(")");
  }
  const int fd = open(g_running.crash_file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  bool saved = fd >= 0;
  for (std::size_t at = 0; saved && at < g_running.size;) {
    const ssize_t w = write(fd, g_running.data + at, g_running.size - at);
    saved = w > 0;
    at += saved ? static_cast<std::size_t>(w) : 0;
  }
  if (fd >= 0) close(fd);
  say(saved ? "; the input is in " : "; could not write the input to ");
  say(g_running.crash_file);
  say("\n");
  raise(sig);  // the default action now (SA_RESETHAND), not blocked (SA_NODEFER)
}

void install_signal_handlers() {
  // An own stack, so that a stack overflow still reaches the handler.
  static char alt_stack[1 << 16];
  stack_t ss{};
  ss.ss_sp = alt_stack;
  ss.ss_size = sizeof alt_stack;
  sigaltstack(&ss, nullptr);
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sa.sa_flags = SA_RESETHAND | SA_NODEFER | SA_ONSTACK;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGILL, SIGTRAP, SIGABRT, SIGSEGV, SIGBUS, SIGFPE}) sigaction(sig, &sa, nullptr);
}

// ---- Deterministic generation ------------------------------------------------------------------

/// The suite's generator (tests/support/rng.hpp: the same numbers with every compiler and
/// library, unlike <random>'s distributions), with the draws the mutations use.
struct Rng {
  vproxq::test::Rng bits;
  std::uint64_t next() { return bits.next(); }
  /// Uniform in [0, n) (0 for n = 0); the bias is irrelevant here.
  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(next() % n); }
  bool one_in(std::size_t n) { return below(n) == 0; }
};

// What the text readers give meaning to: characters, numbers at and past the limits of int,
// int64 and double (all valid JSON), other JSON values, and words that are numbers elsewhere or
// OBJ face corners.
constexpr std::string_view kChars = "0123456789 \t\n\r-+.eE/#,:;{}[]\"\\";
constexpr std::string_view kNumbers[] = {
    "0", "-0", "1", "-1", "3", "255", "256", "65536", "2147483647", "2147483648", "-2147483649",
    "4294967296", "9223372036854775807", "-9223372036854775808", "18446744073709551616",
    "99999999999999999999999", "0.5", "1e308", "-1e308", "1e309", "1e-320", "5e-324", "1.0e-7"};
constexpr std::string_view kWords[] = {"null", "true", "\"\"", "[]", "{}", "nan", "-inf", "inf", "0x1p3",
                                       "1.", ".5", "1//1", "1/1/1", "-2/3"};

/// A number (3 times in 4) or a word.
std::string_view token(Rng& rng) {
  return rng.below(4) != 0 ? kNumbers[rng.below(std::size(kNumbers))] : kWords[rng.below(std::size(kWords))];
}

std::ptrdiff_t off(std::size_t i) { return static_cast<std::ptrdiff_t>(i); }

void insert(Bytes& s, std::size_t at, const std::uint8_t* from, std::size_t n) {
  s.insert(s.begin() + off(at), from, from + n);
}

void insert(Bytes& s, std::size_t at, std::string_view text) {
  insert(s, at, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

void erase(Bytes& s, std::size_t from, std::size_t to) { s.erase(s.begin() + off(from), s.begin() + off(to)); }

/// Where each line starts, and the end: line k is [starts[k], starts[k + 1]). A last line
/// without its newline gets one first, so that moved lines stay lines.
std::vector<std::size_t> line_starts(Bytes& s) {
  if (!s.empty() && s.back() != '\n') s.push_back('\n');
  std::vector<std::size_t> starts{0};
  for (std::size_t i = 0; i + 1 < s.size(); ++i)
    if (s[i] == '\n') starts.push_back(i + 1);
  starts.push_back(s.size());
  return starts;
}

/// One random change to `s`; `other` is a seed (for splices).
void mutate_once(Bytes& s, const Bytes& other, Rng& rng) {
  const std::size_t at = rng.below(s.size() + 1);  // a position, the end included
  switch (rng.below(12)) {
    case 0:  // flip a bit
      if (at < s.size()) s[at] ^= static_cast<std::uint8_t>(1u << rng.below(8));
      break;
    case 1:  // any byte
      if (at < s.size()) s[at] = static_cast<std::uint8_t>(rng.next());
      break;
    case 2:  // 1-4 digits, punctuation, whitespace
      for (std::size_t n = 1 + rng.below(4); n > 0; --n)
        insert(s, at, kChars.substr(rng.below(kChars.size()), 1));
      break;
    case 3:  // a number or a word
      insert(s, at, token(rng));
      break;
    case 4: {  // the next number (digits and points, with a sign) becomes another, or a word
      std::size_t b = at;
      while (b < s.size() && !(s[b] >= '0' && s[b] <= '9')) ++b;
      if (b == s.size()) break;
      std::size_t e = b;
      while (e < s.size() && ((s[e] >= '0' && s[e] <= '9') || s[e] == '.')) ++e;
      if (b > 0 && s[b - 1] == '-') --b;
      erase(s, b, e);
      insert(s, b, token(rng));
      break;
    }
    case 5:  // delete 1 to 64 bytes
      erase(s, at, at + std::min(s.size() - at, 1 + rng.below(std::size_t{1} << rng.below(7))));
      break;
    case 6:  // cut the end
      s.resize(at);
      break;
    case 7:  // 1-8 lines copied to the start of a line
    case 8: {  // 1-8 lines deleted
      const std::vector<std::size_t> starts = line_starts(s);
      const std::size_t lines = starts.size() - 1;
      const std::size_t i = rng.below(lines), j = std::min(lines, i + 1 + rng.below(8));
      if (s.empty()) break;
      const Bytes range(s.begin() + off(starts[i]), s.begin() + off(starts[j]));
      if (rng.one_in(2)) {
        insert(s, starts[rng.below(lines + 1)], range.data(), range.size());
      } else {
        erase(s, starts[i], starts[j]);
      }
      break;
    }
    case 9: {  // two lines swapped
      const std::vector<std::size_t> starts = line_starts(s);
      const std::size_t lines = starts.size() - 1;
      std::size_t p = rng.below(lines), q = rng.below(lines);
      if (p == q) break;
      if (p > q) std::swap(p, q);
      const Bytes first(s.begin() + off(starts[p]), s.begin() + off(starts[p + 1]));
      const Bytes second(s.begin() + off(starts[q]), s.begin() + off(starts[q + 1]));
      // The later line first, so that the earlier one's offsets still hold.
      erase(s, starts[q], starts[q + 1]);
      insert(s, starts[q], first.data(), first.size());
      erase(s, starts[p], starts[p + 1]);
      insert(s, starts[p], second.data(), second.size());
      break;
    }
    case 10:  // splice: this one's beginning, the other's end
      s.resize(at);
      s.insert(s.end(), other.begin() + off(rng.below(other.size() + 1)), other.end());
      break;
    default: {  // up to 64 bytes of the other, inserted
      const std::size_t from = rng.below(other.size() + 1);
      insert(s, at, other.data() + from, std::min(other.size() - from, 1 + rng.below(64)));
      break;
    }
  }
}

/// 0 to max_len bytes (max_len half the time: every field decoded), a quarter of them repeats
/// of earlier bytes (equal coordinates and indices) and some extreme.
Bytes random_bytes(std::size_t max_len, Rng& rng) {
  const std::size_t n = rng.one_in(2) ? max_len : rng.below(max_len + 1);
  Bytes s;
  s.reserve(n);
  constexpr std::uint8_t kExtremes[] = {0x00, 0x01, 0x7f, 0x80, 0xfe, 0xff};
  while (s.size() < n) {
    const std::size_t kind = rng.below(8);
    if (kind < 2 && !s.empty()) {
      s.push_back(s[rng.below(s.size())]);
    } else if (kind == 2) {
      s.push_back(kExtremes[rng.below(std::size(kExtremes))]);
    } else {
      s.push_back(static_cast<std::uint8_t>(rng.next()));
    }
  }
  return s;
}

/// A seed changed once (half of them), twice, 4 or 8 times: most changes make a JSON text
/// invalid, and an input that fails to parse checks little.
Bytes mutant(const std::vector<Bytes>& seeds, Rng& rng) {
  Bytes s = seeds[rng.below(seeds.size())];
  std::size_t n = 1;
  while (n < 8 && rng.one_in(2)) n *= 2;
  for (; n > 0; --n) mutate_once(s, seeds[rng.below(seeds.size())], rng);
  return s;
}

struct Generator {
  const std::vector<Bytes>& seeds;
  std::uint64_t seed;
  std::size_t max_len;
  int join;  // the byte joining two files, or -1

  /// Generated input i: a fresh generator for each, so that any one can be made alone.
  Bytes operator()(std::uint64_t i) const {
    Rng rng{vproxq::test::Rng(vproxq::test::Rng(seed).next() ^ i)};
    // Without seeds, or one time in 16: random bytes.
    if (seeds.empty() || rng.one_in(16)) return random_bytes(max_len, rng);
    if (join < 0) return mutant(seeds, rng);
    // Two files: a seed or a mutant, and the same again, a copy changed once or another
    // mutant (the comparison's interesting cases are valid files that nearly agree).
    Bytes a = rng.one_in(4) ? seeds[rng.below(seeds.size())] : mutant(seeds, rng);
    Bytes b;
    switch (rng.below(4)) {
      case 0: b = a; break;
      case 1: b = mutant(seeds, rng); break;
      default: b = a; mutate_once(b, seeds[rng.below(seeds.size())], rng); break;
    }
    a.push_back(static_cast<std::uint8_t>(join));
    a.insert(a.end(), b.begin(), b.end());
    return a;
  }
};

// ---- Running -----------------------------------------------------------------------------------

bool g_verbose = false;

/// Runs one input, from a buffer of exactly its size (as libFuzzer does: a sanitizer catches
/// reads past the end).
void run_one(const Bytes& input) {
  const std::unique_ptr<std::uint8_t[]> copy(new std::uint8_t[std::max<std::size_t>(input.size(), 1)]);
  std::copy(input.begin(), input.end(), copy.get());
  g_running.data = copy.get();
  g_running.size = input.size();
  if (g_verbose) {
    if (g_running.generated >= 0)
      std::fprintf(stderr, "replay: input %" PRIu64 ": generated input %" PRId64 " of --seed %" PRIu64 ", %zu bytes\n",
                   g_running.index, g_running.generated, g_running.seed, input.size());
    else
      std::fprintf(stderr, "replay: input %" PRIu64 ": %s%s%s, %zu bytes\n", g_running.index, g_running.seed_file,
                   g_running.joined_file ? " joined with " : "", g_running.joined_file ? g_running.joined_file : "",
                   input.size());
    std::fflush(stderr);
  }
  LLVMFuzzerTestOneInput(copy.get(), input.size());
  g_running.data = nullptr;
  ++g_running.index;
}

[[noreturn]] void usage_error(const char* program, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", program, what.c_str());
  std::fprintf(stderr, kUsage, program);
  std::exit(2);
}

Bytes read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  Bytes data{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!in.good() && !in.eof()) {
    std::fprintf(stderr, "cannot read %s\n", file.c_str());
    std::exit(2);
  }
  return data;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string program = fs::path(argv[0]).filename().string();
  std::uint64_t runs = 1000, seed = 1, only = 0, max_seed_size = 1 << 20;
  std::size_t max_len = 256;
  double max_seconds = -1;
  bool has_only = false;
  int join = -1;
  std::string crash_file = program + "-crash.bin";
  std::vector<fs::path> seed_paths;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "-h" || arg == "--help") {
      std::printf(kUsage, program.c_str());
      return 0;
    }
    if (arg.size() < 2 || arg.compare(0, 2, "--") != 0) {
      seed_paths.emplace_back(arg);
      continue;
    }
    if (k + 1 == argc) usage_error(program.c_str(), arg + " needs a value");
    const std::string value = argv[++k];
    char* end = nullptr;
    errno = 0;
    const unsigned long long number = std::strtoull(value.c_str(), &end, arg == "--join" ? 16 : 10);
    const bool numeric = !value.empty() && value[0] != '-' && *end == '\0' && errno == 0;
    if (arg == "--crash-file") {
      crash_file = value;
    } else if (arg == "--max-seconds") {
      max_seconds = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !(max_seconds >= 0))
        usage_error(program.c_str(), "bad " + arg + " " + value);
    } else if (!numeric) {
      usage_error(program.c_str(), "bad or unknown option " + arg + " " + value);
    } else if (arg == "--runs") {
      runs = number;
    } else if (arg == "--seed") {
      seed = number;
    } else if (arg == "--max-len") {
      max_len = static_cast<std::size_t>(number);
    } else if (arg == "--only") {
      only = number;
      has_only = true;
    } else if (arg == "--max-seed-size") {
      max_seed_size = number;
    } else if (arg == "--join" && number <= 0xff) {
      join = static_cast<int>(number);
    } else {
      usage_error(program.c_str(), "bad or unknown option " + arg + " " + value);
    }
  }

  // The seeds: files as given, directories' regular files in name order.
  std::vector<std::string> seed_names;
  std::vector<Bytes> seeds;
  std::size_t skipped = 0;
  for (const fs::path& p : seed_paths) {
    std::vector<fs::path> files;
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      for (const auto& entry : fs::recursive_directory_iterator(p))
        if (entry.is_regular_file()) files.push_back(entry.path());
      std::sort(files.begin(), files.end());
    } else if (fs::is_regular_file(p, ec)) {
      files.push_back(p);
    } else {
      usage_error(program.c_str(), "no such seed file or directory: " + p.string());
    }
    for (const fs::path& f : files) {
      if (fs::file_size(f) > max_seed_size) {
        ++skipped;
        continue;
      }
      seed_names.push_back(f.string());
      seeds.push_back(read_file(f));
    }
  }

  const char* verbose = std::getenv("VPROXQ_REPLAY_VERBOSE");
  g_verbose = verbose != nullptr && *verbose != '\0' && std::string_view(verbose) != "0";
  g_running.seed = seed;
  g_running.crash_file = crash_file.c_str();
  install_signal_handlers();
  if (LLVMFuzzerInitialize != nullptr) LLVMFuzzerInitialize(&argc, &argv);

  const auto start = std::chrono::steady_clock::now();
  auto seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const Generator generate{seeds, seed, max_len, join};
  if (has_only) {
    g_running.generated = static_cast<std::int64_t>(only);
    run_one(generate(only));
    std::printf("%s: generated input %" PRIu64 " of --seed %" PRIu64 " passed\n", program.c_str(), only, seed);
    return 0;
  }

  // The seeds: each one, or with --join every pair (each file with itself included).
  for (std::size_t a = 0; a < seeds.size(); ++a) {
    g_running.seed_file = seed_names[a].c_str();
    if (join < 0) {
      run_one(seeds[a]);
      continue;
    }
    for (std::size_t b = 0; b < seeds.size(); ++b) {
      g_running.joined_file = seed_names[b].c_str();
      Bytes pair = seeds[a];
      pair.push_back(static_cast<std::uint8_t>(join));
      pair.insert(pair.end(), seeds[b].begin(), seeds[b].end());
      run_one(pair);
    }
  }
  const std::uint64_t seed_inputs = g_running.index;

  bool out_of_time = false;
  for (std::uint64_t i = 0; i < runs; ++i) {
    // The clock is read every 16 inputs: the fastest harnesses take microseconds.
    if (max_seconds >= 0 && i % 16 == 0 && seconds() > max_seconds) {
      out_of_time = true;
      break;
    }
    g_running.generated = static_cast<std::int64_t>(i);
    run_one(generate(i));
  }

  const std::string skipped_text = skipped ? ", " + std::to_string(skipped) + " skipped as too large" : "";
  std::printf("%s: %" PRIu64 " inputs (%" PRIu64 " from %zu seed files%s, %" PRIu64 " generated with --seed %" PRIu64
              "%s) in %.1f s\n",
              program.c_str(), g_running.index, seed_inputs, seeds.size(), skipped_text.c_str(),
              g_running.index - seed_inputs, seed, out_of_time ? ", stopped at --max-seconds" : "", seconds());
  return 0;
}
