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

void set_path(Value& root, std::string_view dotted, Value v) {
    Value* node = &root;
    while (true) {
        if (node->is_null()) node->make_table();
        auto dot = dotted.find('.');
        std::string key(dotted.substr(0, dot));
        if (key.empty()) throw ConfigError("empty key in path");
        auto& table = node->as_table_mut();
        if (dot == std::string_view::npos) {
            table[key] = std::move(v);
            return;
        }
        node = &table[key];
        dotted.remove_prefix(dot + 1);
    }
}

const Value* find_path(const Value& root, std::string_view dotted) {
    const Value* node = &root;
    while (node) {
        auto dot = dotted.find('.');
        node = node->find(dotted.substr(0, dot));
        if (dot == std::string_view::npos) return node;
        dotted.remove_prefix(dot + 1);
    }
    return nullptr;
}

}  // namespace sphfsi
