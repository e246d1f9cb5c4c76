// The one normalization of caption text, used by the piece-model trainer and
// by every model that reads captions, so that "A Dog trots, 3 times!" and
// "a dog trots three times" are the same input:
//   lower case (ASCII letters; other UTF-8 bytes are kept as they are),
//   numbers 0-20 spelled out ("3" -> "three"; larger ones stay digits),
//   apostrophes dropped ("dog's" -> "dogs"), every other ASCII punctuation
//   mark a word break ("left-hand" -> "left hand"), single spaces, no ends.
//
//   std::string text = checked_caption("A Dog trots, 3 times!", "query");  // "a dog trots three times"
//   std::vector<std::string> words = caption_words(text);                  // {"a", "dog", ...}
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace nec::text {

std::string normalize_caption(std::string_view caption);

// normalize_caption, refusing what no model can read: InputError(where, 0,
// "empty") or "no letters in '<caption>'".
std::string checked_caption(std::string_view caption, const std::string& where);

// The words of a normalized caption, or of any text: split on spaces, no empty words.
std::vector<std::string> caption_words(std::string_view normalized);

}  // namespace nec::text
