#include "io/hdf5_util.hpp"

#include <algorithm>

namespace vproxq::h5 {

namespace {

// No clean-up of HDF5's own at exit: every file is closed explicitly (and a result file that
// was not closed successfully is never committed), while the library's exit handler, after
// an H5Fclose that failed (a full disk), closes that file again and crashes. Runs before
// main(), hence before any other HDF5 call, as H5dont_atexit() requires.
const bool kNoAtexitCleanup = [] { return H5dont_atexit() >= 0; }();

// H5Ewalk2 callback: keeps the description of the last (innermost) entry visited.
herr_t keep_innermost(unsigned /*n*/, const H5E_error2_t* err, void* client) {
  auto* out = static_cast<std::string*>(client);
  if (err != nullptr && err->desc != nullptr && err->desc[0] != '\0') *out = err->desc;
  return 0;
}

}  // namespace

std::string last_error_message() {
  std::string message;
  // Downward: from the API call to the innermost function, where the cause is named.
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, keep_innermost, &message);
  return message;
}

std::string failure_text(const char* call, const std::string& file, const std::string& object) {
  std::string text = std::string(call) + " failed for '" + file + "'";
  if (!object.empty()) text += " (" + object + ")";
  std::string detail = last_error_message();
  // HDF5's descriptions can span lines (a failed write lists its numbers on a second line).
  std::replace(detail.begin(), detail.end(), '\n', ' ');
  if (!detail.empty()) text += ": " + detail;
  return text;
}

Handle vlen_string_type() {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.valid()) return type;
  if (H5Tset_size(type.get(), H5T_VARIABLE) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0) {
    return Handle();
  }
  return type;
}

}  // namespace vproxq::h5
