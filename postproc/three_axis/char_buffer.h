// The three-axis post's output buffer: bytes written through a pointer, no
// string per piece (internal to postproc/three_axis/).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <memory>
#include <string_view>

#include "gcode/nc_writer.h"

namespace volmap::post {

// A growable byte buffer written through a pointer: room(n) makes n bytes
// writable at the end without initialising them (std::string::resize would
// zero them), commit(end) keeps what was written up to end. The writer's
// numbers and edited lines go straight into it, no string per piece.
class CharBuffer {
 public:
  char* room(std::size_t n) {
    if (cap_ - size_ < n) grow(n);
    return data_.get() + size_;
  }
  void commit(const char* end) { size_ = static_cast<std::size_t>(end - data_.get()); }
  void append(std::string_view s) {
    std::memcpy(room(s.size()), s.data(), s.size());
    size_ += s.size();
  }
  void assign(std::string_view s) {
    size_ = 0;
    append(s);
  }
  void clear() { size_ = 0; }
  std::size_t size() const { return size_; }
  const char* data() const { return data_.get(); }
  std::string_view view() const { return {data_.get(), size_}; }

 private:
  void grow(std::size_t n) {
    const std::size_t cap = std::max(2 * cap_, size_ + n);
    std::unique_ptr<char[]> bigger(new char[cap]);  // uninitialised, as room() promises
    if (size_) std::memcpy(bigger.get(), data_.get(), size_);
    data_ = std::move(bigger);
    cap_ = cap;
  }
  std::unique_ptr<char[]> data_;
  std::size_t size_ = 0, cap_ = 0;
};

// format_number(value, dec) appended to w.
inline void append_number(CharBuffer& w, double value, int dec) {
  char* p = w.room(nc::kNumberRoom);
  if (const char* end = nc::format_number_fast(value, dec, p))
    w.commit(end);
  else
    w.append(nc::format_number(value, dec));
}

}  // namespace volmap::post
