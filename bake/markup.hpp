#pragma once
/// Text inside HTML and XML (the report, the JUnit file): escaped so that a frame or body name
/// cannot end an attribute or open a tag.

#include <string>
#include <string_view>

namespace softbake {

/// `text` with &, <, >, " and ' as entities, and control characters other than tab and newline
/// (which XML 1.0 cannot hold) as U+FFFD.
std::string escapeMarkup(std::string_view text);

}  // namespace softbake
