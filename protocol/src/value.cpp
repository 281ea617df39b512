#include "sphfsi/protocol/value.hpp"

namespace sphfsi {
namespace {
[[noreturn]] void type_error(std::string_view path, const char* want, const Value& v) {
    std::string where = path.empty() ? std::string("value") : "'" + std::string(path) + "'";
    throw ConfigError(where + " must be " + want + ", not " + v.type_name());
}
}  // namespace

const char* Value::type_name() const {
    switch (data_.index()) {
        case 0: return "nothing";
        case 1: return "a boolean";
        case 2: return "an integer";
        case 3: return "a float";
        case 4: return "a string";
        case 5: return "an array";
        default: return "a table";
    }
}

bool Value::as_bool(std::string_view path) const {
    if (!is_bool()) type_error(path, "a boolean", *this);
    return std::get<bool>(data_);
}
std::int64_t Value::as_int(std::string_view path) const {
    if (!is_int()) type_error(path, "an integer", *this);
    return std::get<std::int64_t>(data_);
}
double Value::as_double(std::string_view path) const {
    if (is_int()) return static_cast<double>(std::get<std::int64_t>(data_));
    if (!is_double()) type_error(path, "a number", *this);
    return std::get<double>(data_);
}
const std::string& Value::as_string(std::string_view path) const {
    if (!is_string()) type_error(path, "a string", *this);
    return std::get<std::string>(data_);
}
const Value::Array& Value::as_array(std::string_view path) const {
    if (!is_array()) type_error(path, "an array", *this);
    return std::get<Array>(data_);
}
const Value::Table& Value::as_table(std::string_view path) const {
    if (!is_table()) type_error(path, "a table", *this);
    return std::get<Table>(data_);
}
Value::Array& Value::as_array_mut() {
    if (!is_array()) type_error("", "an array", *this);
    return std::get<Array>(data_);
}
Value::Table& Value::as_table_mut() {
    if (!is_table()) type_error("", "a table", *this);
    return std::get<Table>(data_);
}

bool Value::contains(std::string_view key) const { return find(key) != nullptr; }

const Value* Value::find(std::string_view key) const {
    if (!is_table()) return nullptr;
    const auto& t = std::get<Table>(data_);
    auto it = t.find(key);
    return it == t.end() ? nullptr : &it->second;
}

const Value& Value::at(std::string_view key) const {
    if (const Value* v = find(key)) return *v;
    throw ConfigError("missing key '" + std::string(key) + "'");
}

double Value::number_or(std::string_view key, double fallback) const {
    const Value* v = find(key);
    return v ? v->as_double(key) : fallback;
}

std::string Value::string_or(std::string_view key, std::string fallback) const {
    const Value* v = find(key);
    return v ? v->as_string(key) : fallback;
}

std::vector<double> Value::as_doubles(std::string_view path) const {
    std::vector<double> out;
    for (const Value& v : as_array(path)) out.push_back(v.as_double(path));
    return out;
}

namespace {
// One step of a dotted path: "members[2]" is key "members", index 2; "dp" is key "dp", no index.
struct PathStep {
    std::string key;
    long index = -1;
};

PathStep parse_step(std::string_view part, std::string_view whole) {
    PathStep step;
    auto open = part.find('[');
    step.key = std::string(part.substr(0, open));
    if (step.key.empty()) throw ConfigError("empty key in '" + std::string(whole) + "'");
    if (open == std::string_view::npos) return step;
    if (part.back() != ']') throw ConfigError("expected key[index] in '" + std::string(whole) + "'");
    std::string digits(part.substr(open + 1, part.size() - open - 2));
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos)
        throw ConfigError("index must be a non-negative integer in '" + std::string(whole) + "'");
    if (digits.size() > 9) throw ConfigError("index " + digits + " is out of range in '" + std::string(whole) + "'");
    step.index = std::stol(digits);
    return step;
}
}  // namespace

void set_path(Value& root, std::string_view dotted, Value v) {
    const std::string_view whole = dotted;
    Value* node = &root;
    while (true) {
        if (node->is_null()) node->make_table();
        auto dot = dotted.find('.');
        PathStep step = parse_step(dotted.substr(0, dot), whole);
        if (!node->is_table()) {  // e.g. members.0.n_elements, where members is an array of tables
            const std::string walked(whole.substr(0, whole.size() - dotted.size() - 1));
            throw ConfigError("'" + std::string(whole) + "': '" + walked + "' is " +
                              (node->is_array() ? "an array; address an entry as " + walked + "[INDEX]" : "not a table"));
        }
        auto& table = node->as_table_mut();
        Value* child = &table[step.key];
        if (step.index >= 0) {  // an entry of an array of tables, e.g. [[structure.members]]
            // Which entries there are, or that there is no array to index: "no entry 0 of 'boxes'" read as if
            // 'boxes' existed (a review, 2026-11-28). An entry is changed here, never added.
            const std::string array = std::string(whole.substr(0, whole.size() - dotted.size())) + step.key;
            if (child->is_null())
                throw ConfigError("'" + std::string(whole) + "': there is no '" + array + "' to take entry " +
                                  std::to_string(step.index) + " of");
            if (!child->is_array())
                throw ConfigError("'" + std::string(whole) + "': '" + array + "' is " + child->type_name() +
                                  ", not an array to take entry " + std::to_string(step.index) + " of");
            const std::size_t n = child->as_array().size();
            if (static_cast<std::size_t>(step.index) >= n)
                throw ConfigError("'" + std::string(whole) + "': '" + array + "' has " +
                                  (n == 0 ? std::string("no entries") :
                                   n == 1 ? std::string("one entry, ") + array + "[0]" :
                                            std::to_string(n) + " entries, " + array + "[0] to " + array + "[" +
                                                std::to_string(n - 1) + "]"));
            child = &child->as_array_mut()[static_cast<std::size_t>(step.index)];
        }
        if (dot == std::string_view::npos) {
            *child = std::move(v);
            return;
        }
        node = child;
        dotted.remove_prefix(dot + 1);
    }
}

const Value* find_path(const Value& root, std::string_view dotted) {
    const std::string_view whole = dotted;
    const Value* node = &root;
    while (node) {
        auto dot = dotted.find('.');
        PathStep step = parse_step(dotted.substr(0, dot), whole);
        node = node->find(step.key);
        if (node && step.index >= 0)
            node = node->is_array() && static_cast<std::size_t>(step.index) < node->as_array().size()
                       ? &node->as_array()[static_cast<std::size_t>(step.index)]
                       : nullptr;
        if (dot == std::string_view::npos) return node;
        dotted.remove_prefix(dot + 1);
    }
    return nullptr;
}

}  // namespace sphfsi
