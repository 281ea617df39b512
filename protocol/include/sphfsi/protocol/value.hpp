#pragma once
// A dynamically typed configuration tree: what a scene section looks like after TOML parsing and
// what travels inside INIT as a msgpack map. Participants read their settings from it.
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace sphfsi {

class ConfigError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class Value {
public:
    using Array = std::vector<Value>;
    using Table = std::map<std::string, Value, std::less<>>;
    using Data = std::variant<std::monostate, bool, std::int64_t, double, std::string, Array, Table>;

    Value() = default;
    Value(bool b) : data_(b) {}
    Value(int i) : data_(std::int64_t{i}) {}
    Value(std::int64_t i) : data_(i) {}
    Value(double d) : data_(d) {}
    Value(const char* s) : data_(std::string(s)) {}
    Value(std::string s) : data_(std::move(s)) {}
    Value(Array a) : data_(std::move(a)) {}
    Value(Table t) : data_(std::move(t)) {}

    bool is_null() const { return std::holds_alternative<std::monostate>(data_); }
    bool is_bool() const { return std::holds_alternative<bool>(data_); }
    bool is_int() const { return std::holds_alternative<std::int64_t>(data_); }
    bool is_double() const { return std::holds_alternative<double>(data_); }
    bool is_number() const { return is_int() || is_double(); }
    bool is_string() const { return std::holds_alternative<std::string>(data_); }
    bool is_array() const { return std::holds_alternative<Array>(data_); }
    bool is_table() const { return std::holds_alternative<Table>(data_); }

    // Typed access; throws ConfigError naming `path` (the dotted key, for messages) on a type mismatch.
    bool as_bool(std::string_view path = "") const;
    std::int64_t as_int(std::string_view path = "") const;
    double as_double(std::string_view path = "") const;  // ints widen to double
    const std::string& as_string(std::string_view path = "") const;
    const Array& as_array(std::string_view path = "") const;
    const Table& as_table(std::string_view path = "") const;
    Array& as_array_mut();
    Table& as_table_mut();
    Table& make_table() { return data_.emplace<Table>(); }  // turns this value into an empty table

    // Table look-ups. at() throws ConfigError("missing key ...") when absent.
    bool contains(std::string_view key) const;
    const Value& at(std::string_view key) const;
    const Value* find(std::string_view key) const;
    double number_or(std::string_view key, double fallback) const;
    std::string string_or(std::string_view key, std::string fallback) const;

    // Reads an array of numbers (e.g. a 2-vector).
    std::vector<double> as_doubles(std::string_view path = "") const;

    const char* type_name() const;
    const Data& data() const { return data_; }

    // 1-based line in the scene file this value came from; 0 when unknown (e.g. received over the wire);
    // kFromOverride when a --set on the command line gave it.
    static constexpr int kFromOverride = -1;
    int line = 0;

private:
    Data data_;
};

// Sets the value at a dotted path ("fluid.dp"), creating intermediate tables; used by --set overrides.
void set_path(Value& root, std::string_view dotted, Value v);
const Value* find_path(const Value& root, std::string_view dotted);

}  // namespace sphfsi
