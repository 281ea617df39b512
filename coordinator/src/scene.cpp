#include "sphfsi/coordinator/scene.hpp"

#include "sphfsi/protocol/codec.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <toml++/toml.h>

namespace sphfsi::coordinator {
namespace {

// `in_file`: the node is the scene file's, so an error names its line (an override's text is "x = ..." on line 1,
// and apply_override names the --set instead).
Value from_toml(const toml::node& node, const std::string& path, bool in_file) {
    Value v;
    if (auto t = node.as_table()) {
        Value::Table out;
        for (const auto& [k, child] : *t) {
            std::string key(k.str());
            out.emplace(key, from_toml(child, path.empty() ? key : path + "." + key, in_file));
        }
        v = Value(std::move(out));
    } else if (auto a = node.as_array()) {
        Value::Array out;
        for (const auto& child : *a) out.push_back(from_toml(child, path, in_file));
        v = Value(std::move(out));
    } else if (auto s = node.as_string()) {
        v = Value(s->get());
    } else if (auto i = node.as_integer()) {
        v = Value(static_cast<std::int64_t>(i->get()));
    } else if (auto f = node.as_floating_point()) {
        v = Value(f->get());
    } else if (auto b = node.as_boolean()) {
        v = Value(b->get());
    } else {
        throw ConfigError((in_file ? "line " + std::to_string(node.source().begin.line) + ": " : std::string()) + "key '" +
                          path + "': dates and times are not allowed in scenes");
    }
    v.line = static_cast<int>(node.source().begin.line);
    return v;
}

std::string read_file(const std::filesystem::path& file) {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) throw ConfigError(file.string() + ": is a directory, not a scene file");
    // Only a regular file, and not a huge one: /dev/zero was read until memory ran out (std::bad_alloc, an
    // abort) and a FIFO without a writer hung `check` (a review, 2026-11-28). A missing file falls through to
    // the "cannot read" below.
    constexpr std::uintmax_t max_bytes = 16u << 20;
    if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec))
        throw ConfigError(file.string() + ": is not a regular file, so not a scene file");
    if (const auto size = std::filesystem::file_size(file, ec); !ec && size > max_bytes)
        throw ConfigError(file.string() + ": " + std::to_string(size) + " bytes; a scene file is at most " +
                          std::to_string(max_bytes) + " bytes (16 MiB)");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw ConfigError(file.string() + ": cannot read the scene file");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// An override's values are marked as such (Value::kFromOverride), children included: a nested --set table's
// keys would otherwise carry line 1 of the text "x = ..." they were parsed from.
void mark_override(Value& v) {
    v.line = Value::kFromOverride;
    if (v.is_table())
        for (auto& [k, child] : v.as_table_mut()) mark_override(child);
    else if (v.is_array())
        for (auto& child : v.as_array_mut()) mark_override(child);
}

}  // namespace

void apply_override(Value& root, const std::string& assignment) {
    auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw ConfigError("--set " + assignment + ": expected key.path=value");
    std::string key = assignment.substr(0, eq);
    std::string text = assignment.substr(eq + 1);
    Value v;
    try {
        auto doc = toml::parse("x = " + text);
        v = from_toml(*doc.get("x"), key, false);
    } catch (const ConfigError& e) {  // a date: named as the --set it came from, as every other --set error is
        throw ConfigError("--set " + assignment + ": " + e.what());
    } catch (const toml::parse_error& e) {
        // A bare word such as wcsph is meant as a string; what starts like a number, array, table or quoted
        // string and does not parse (1e400, [1, 2) is a mistake, not a string.
        if (!text.empty() && std::string_view("0123456789+-[{\"'").find(text.front()) != std::string_view::npos)
            throw ConfigError("--set " + assignment + ": the value is not valid TOML (" + std::string(e.description()) + ")");
        v = Value(text);
    }
    mark_override(v);
    try {
        set_path(root, key, std::move(v));
    } catch (const ConfigError& e) {  // no such entry, an array addressed as a table: which --set it was
        throw ConfigError("--set " + assignment + ": " + e.what());
    }
}

std::optional<std::vector<std::string>> Scene::custom_program(std::string_view role) const {
    const Value* p = find_path(tree, "participants");
    const Value* cmd = p ? p->find(role) : nullptr;
    if (!cmd) return std::nullopt;
    std::vector<std::string> words;
    std::istringstream in(cmd->as_string());
    for (std::string w; in >> w;) {
        // Paths are relative to the scene file, so scenes are portable: the program when it has a slash, and
        // arguments written ./x or ../x. Other arguments with a slash (--opt=a/b, tcp://host) are left alone.
        const bool program = words.empty();
        const bool relative = w.starts_with("./") || w.starts_with("../") ||
                              (program && w.find('/') != std::string::npos && w.front() != '/');
        if (relative) w = (file.parent_path() / w).lexically_normal().string();
        words.push_back(w);
    }
    return words;
}

namespace {
// Why argv[0] of a participant command cannot be started, or "" when it can (as execvp would find it).
std::string unrunnable(const std::string& program) {
    auto runnable = [](const std::filesystem::path& p) {
        std::error_code ec;
        return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
    };
    if (program.find('/') != std::string::npos)
        return runnable(program) ? "" : "is not an executable file";
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "/usr/local/bin:/usr/bin:/bin");
    for (std::string dir; std::getline(dirs, dir, ':');)
        if (runnable(std::filesystem::path(dir.empty() ? "." : dir) / program)) return "";
    return "is not an executable file on PATH";
}
}  // namespace

Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides, bool programs_run) {
    Scene scene = parse_scene(read_file(file), file, overrides);
    // A participant command that cannot start passed `check`, and a run then failed only after creating its
    // record (with --overwrite, in place of the earlier one; a review, 2026-11-28). Under --listen the
    // commands are not run, and the program may well live on another machine: nothing is looked for then.
    if (!programs_run) return scene;
    for (const char* role : {"fluid", "structure"})
        if (const auto argv = scene.custom_program(role); argv && !argv->empty())
            if (const std::string why = unrunnable(argv->front()); !why.empty())
                throw ConfigError(file.string() + ": key 'participants." + role + "': the program '" +
                                  protocol::printable(argv->front()) + "' " + why);
    return scene;
}

Scene parse_scene(std::string text, const std::filesystem::path& file, const std::vector<std::string>& overrides) {
    Scene scene;
    scene.file = file;
    scene.text = std::move(text);
    scene.overrides = overrides;
    Value raw;
    try {
        raw = from_toml(toml::parse(scene.text, file.string()), "", true);
    } catch (const toml::parse_error& e) {
        throw ConfigError(file.string() + ":" + std::to_string(e.source().begin.line) + ": not valid TOML: " +
                          std::string(e.description()));
    } catch (const ConfigError& e) {
        throw ConfigError(file.string() + ": " + e.what());
    }
    for (const auto& o : overrides) {
        try {
            apply_override(raw, o);
        } catch (const ConfigError& e) {
            throw ConfigError(file.string() + ": " + e.what());
        }
    }
    // A coupled scene's [coupling] may be left out: every key has a default.
    if (raw.is_table() && raw.contains("fluid") && raw.contains("structure") && !raw.contains("coupling"))
        set_path(raw, "coupling", Value(Value::Table{}));
    std::vector<std::string> external;
    if (const Value* p = raw.find("participants"); p && p->is_table())
        for (const auto& [role, cmd] : p->as_table()) external.push_back(role);
    schema::Errors errors;
    scene.tree = scene_schema(external).validate(raw, "", errors);
    schema::throw_if_any(errors, file.string());
    return scene;
}

}  // namespace sphfsi::coordinator
