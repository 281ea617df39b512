#pragma once
// A scene: the TOML file, its overrides, and the validated tree every part of a run reads from.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sphfsi/protocol/schema.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::coordinator {

struct Scene {
    std::filesystem::path file;      // where it came from (for messages and relative paths)
    std::string text;                // the file's text, recorded verbatim
    std::vector<std::string> overrides;  // the --set arguments, recorded
    Value tree;                      // validated, defaults filled in

    bool has(std::string_view role) const { return tree.contains(role); }
    const Value& section(std::string_view role) const { return tree.at(role); }
    // The command that starts `role`: the built-in program unless [participants] names another.
    std::optional<std::vector<std::string>> custom_program(std::string_view role) const;
};

// Parses "a.b.c=value" (value in TOML syntax; bare words are strings) into `root`.
void apply_override(Value& root, const std::string& assignment);

// Reads, overrides and validates. Throws ConfigError with every problem, each naming the file, the
// line where known, the key and the allowed values. Nothing runs on an invalid scene.
// `programs_run`: the [participants] commands will be started (not under --listen), so each must exist.
Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {},
                 bool programs_run = true);
// The same from the scene's text (e.g. as a checkpoint recorded it); `file` names it in messages and
// anchors relative program paths.
Scene parse_scene(std::string text, const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

// The schema of a whole scene; `external` lists roles run by a custom program (their section is
// passed through to it unchecked, and the program validates it at INIT).
schema::TableSchema scene_schema(const std::vector<std::string>& external = {});

// Markdown reference of every key (docs/scenes.md embeds it).
std::string scene_reference();

}  // namespace sphfsi::coordinator
