#pragma once
// One line per message on stderr, prefixed with who speaks ("lightfarm" or the actor's name).
#include <string>

namespace lf {

void set_log_name(std::string name);
void log_info(const std::string& message);
void log_warn(const std::string& message);
void log_error(const std::string& message);
// Debug lines appear only when LIGHTFARM_DEBUG is set in the environment.
void log_debug(const std::string& message);

// "1.5 s", "10 s": a duration as messages show it.
std::string seconds_text(double seconds);

}  // namespace lf
