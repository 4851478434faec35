// Internal to mdn_io: a compact list of strings (one per vertex or face) for the text formats,
// which keep what follows the coordinates on each line (colours, texture indices) verbatim.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mdn::io::detail {

class TextColumn {
 public:
  void push_back(std::string_view text) {
    if (!text.empty()) any_ = true;
    blob_.append(text);
    ends_.push_back(blob_.size());
  }
  std::string_view operator[](std::size_t i) const {
    const std::size_t begin = i == 0 ? 0 : ends_[i - 1];
    return std::string_view(blob_).substr(begin, ends_[i] - begin);
  }
  std::size_t size() const { return ends_.size(); }
  bool any() const { return any_; }

 private:
  std::string blob_;
  std::vector<std::size_t> ends_;
  bool any_ = false;
};

// Trims spaces, tabs and carriage returns on both sides.
inline std::string_view trim(std::string_view text) {
  const std::size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  const std::size_t end = text.find_last_not_of(" \t\r");
  return text.substr(begin, end - begin + 1);
}

}  // namespace mdn::io::detail
