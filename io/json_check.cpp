#include "io/json_check.hpp"

#include <nlohmann/json.hpp>

#include <set>
#include <vector>

namespace vproxq {

namespace {

using json = nlohmann::json;

/// SAX handler that stops (returns false) at the first problem, which it keeps.
class StructureCheck final : public nlohmann::json_sax<json> {
 public:
  StructureCheck(int max_depth, bool unique_keys, bool integers_fit)
      : max_depth_(max_depth), unique_keys_(unique_keys), integers_fit_(integers_fit) {}

  const std::string& problem() const { return problem_; }

  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t& text) override {
    if (!integers_fit_ || text.find_first_of(".eE") != string_t::npos) return true;
    problem_ = "the integer " + text + " does not fit in 64 bits";
    return false;
  }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override {
    if (unique_keys_) keys_.emplace_back();
    return enter();
  }
  bool key(string_t& k) override {
    if (!unique_keys_ || keys_.back().insert(k).second) return true;
    problem_ = "the key " + json(k).dump(-1, ' ', false, json::error_handler_t::replace) + " appears twice in one object";
    return false;
  }
  bool end_object() override {
    if (unique_keys_) keys_.pop_back();
    --depth_;
    return true;
  }
  bool start_array(std::size_t) override { return enter(); }
  bool end_array() override {
    --depth_;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;  // the parse that follows reports it
  }

 private:
  bool enter() {
    if (++depth_ <= max_depth_) return true;
    problem_ = "nested more than " + std::to_string(max_depth_) + " levels deep";
    return false;
  }

  int max_depth_;
  bool unique_keys_, integers_fit_;
  int depth_ = 0;
  std::vector<std::set<std::string>> keys_;  ///< per object being read, its keys so far
  std::string problem_;
};

}  // namespace

std::string json_structure_problem(std::istream& in, int max_depth, bool unique_keys, bool integers_fit) {
  StructureCheck check(max_depth, unique_keys, integers_fit);
  json::sax_parse(in, &check, nlohmann::detail::input_format_t::json, /*strict=*/true);
  return check.problem();
}

}  // namespace vproxq
