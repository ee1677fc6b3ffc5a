#include "io/hdf5_util.hpp"

namespace vproxq::h5 {

namespace {

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
  const std::string detail = last_error_message();
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
