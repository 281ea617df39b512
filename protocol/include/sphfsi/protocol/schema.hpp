#pragma once
// Declarative scene-section schemas. Each solver library declares the keys it accepts (type, unit,
// range, allowed values, default); the coordinator validates a whole scene against them before
// anything starts, and participants re-validate what INIT hands them. The same declarations print
// the key reference in docs/scenes.md (`sphfsi schema`), so the docs cannot drift from the code.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sphfsi/protocol/value.hpp"

namespace sphfsi::schema {

class TableSchema;

// Collected problems, each already phrased "key 'a.b': what is wrong; allowed: ...".
struct Errors {
    std::vector<std::string> items;
    void add(const Value* at, std::string message);
    bool empty() const { return items.empty(); }
};

class Field {
public:
    enum class Kind { Number, Integer, Boolean, String, Choice, Vector, Table, TableArray, FreeTable };

    Field(std::string name, Kind kind, std::string doc);

    Field& unit(std::string u) { unit_ = std::move(u); return *this; }
    Field& greater_than(double x) { lo_ = x; lo_open_ = true; return *this; }
    Field& at_least(double x) { lo_ = x; lo_open_ = false; return *this; }
    Field& less_than(double x) { hi_ = x; hi_open_ = true; return *this; }
    Field& at_most(double x) { hi_ = x; hi_open_ = false; return *this; }
    Field& required() { required_ = true; return *this; }
    Field& fallback(Value v) { fallback_ = std::move(v); return *this; }

    const std::string& name() const { return name_; }
    Kind kind() const { return kind_; }
    bool is_required() const { return required_; }
    TableSchema* table() const { return table_.get(); }

    // The allowed values in words, e.g. "a number > 0 and <= 0.1 (m)".
    std::string allowed() const;
    Value validate(const Value& v, const std::string& path, Errors& errors) const;
    void document(const std::string& prefix, std::string& out) const;

private:
    friend class TableSchema;
    std::string name_, doc_, unit_;
    Kind kind_;
    bool required_ = false;
    std::optional<Value> fallback_;
    std::optional<double> lo_, hi_;
    bool lo_open_ = false, hi_open_ = false;
    std::vector<std::string> choices_;
    std::size_t length_ = 0;  // Vector: exact length (0 = any)
    std::shared_ptr<TableSchema> table_;
};

class TableSchema {
public:
    explicit TableSchema(std::string doc = "") : doc_(std::move(doc)) {}

    Field& number(std::string name, std::string doc);
    Field& integer(std::string name, std::string doc);
    Field& boolean(std::string name, std::string doc);
    Field& string(std::string name, std::string doc);
    Field& choice(std::string name, std::vector<std::string> allowed, std::string doc);
    Field& vector(std::string name, std::size_t length, std::string doc);  // array of numbers
    // A sub-table with its own keys; present only when the input has it, unless marked required().
    TableSchema& table(std::string name, std::string doc, bool required = false);
    TableSchema& table_array(std::string name, std::string doc);  // [[name]] entries
    Field& free_table(std::string name, std::string doc);         // passed through unchecked

    // A cross-key rule run after the keys themselves validated (e.g. "the water fits in the tank").
    using Check = std::function<void(const Value& table, const std::string& path, Errors&)>;
    TableSchema& check(Check c) { checks_.push_back(std::move(c)); return *this; }

    // Returns `input` with defaults filled in; problems go to `errors` (unknown keys included).
    Value validate(const Value& input, const std::string& path, Errors& errors) const;
    // Markdown reference of every key (used for docs/scenes.md).
    std::string document(const std::string& path) const;
    const std::vector<Field>& fields() const { return fields_; }
    const std::string& doc() const { return doc_; }

private:
    Field& add(Field f);
    std::string doc_;
    std::vector<Field> fields_;
    std::vector<Check> checks_;
};

// Throws ConfigError listing every problem when `errors` is not empty; `source` prefixes each line.
void throw_if_any(const Errors& errors, const std::string& source);

// A number in a scene message: six significant digits where they are the number itself, else every digit it
// takes to read it back (a refused 1000000.5 had printed as "1e+06" beside "allowed: <= 1e+06"; a box 1e-7 m
// outside the tank as on its edge: a review, 2026-11-28). Every scene check quotes numbers with it.
std::string number_text(double x);

}  // namespace sphfsi::schema
