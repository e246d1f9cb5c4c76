// Caption normalization (caption_text.h).
#include "nec/text/caption_text.h"

#include "nec/motion/error.h"

#include <array>

namespace nec::text {
namespace {

constexpr std::array<const char*, 21> kNumberWords = {
    "zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
    "eleven", "twelve", "thirteen", "fourteen", "fifteen", "sixteen", "seventeen", "eighteen", "nineteen", "twenty"};

bool is_ascii_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Appends `word` to `out` after one space (none at the start).
void append_word(std::string& out, std::string_view word) {
  if (word.empty()) return;
  if (!out.empty()) out += ' ';
  out += word;
}

}  // namespace

std::string normalize_caption(std::string_view caption) {
  std::string out, word;
  auto flush = [&] {
    append_word(out, word);
    word.clear();
  };
  for (size_t i = 0; i < caption.size();) {
    const char c = caption[i];
    if (is_digit(c)) {
      // A number is a word of its own ("3times" -> "three times").
      flush();
      size_t end = i;
      while (end < caption.size() && is_digit(caption[end])) ++end;
      const std::string_view digits = caption.substr(i, end - i);
      const bool small = digits.size() <= 2 && std::stoi(std::string(digits)) <= 20;
      append_word(out, small ? std::string_view(kNumberWords[std::stoi(std::string(digits))]) : digits);
      i = end;
      continue;
    }
    if (is_ascii_letter(c)) {
      word += static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    } else if (static_cast<unsigned char>(c) >= 0x80) {
      word += c;  // UTF-8 letters of other scripts stay as they are
    } else if (c != '\'') {
      flush();  // spaces, control characters and punctuation break words
    }
    ++i;
  }
  flush();
  return out;
}

std::string checked_caption(std::string_view caption, const std::string& where) {
  const std::string text = normalize_caption(caption);
  if (text.empty()) {
    throw InputError(where, 0, caption.empty() ? "empty" : "no letters in '" + std::string(caption) + "'");
  }
  bool letter = false;
  for (const char c : text) letter = letter || is_ascii_letter(c) || static_cast<unsigned char>(c) >= 0x80;
  if (!letter) throw InputError(where, 0, "no letters in '" + std::string(caption) + "'");
  return text;
}

std::vector<std::string> caption_words(std::string_view normalized) {
  std::vector<std::string> words;
  size_t start = 0;
  while (start < normalized.size()) {
    size_t end = normalized.find(' ', start);
    if (end == std::string_view::npos) end = normalized.size();
    if (end > start) words.emplace_back(normalized.substr(start, end - start));
    start = end + 1;
  }
  return words;
}

}  // namespace nec::text
