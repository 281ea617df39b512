#include "sphfsi/protocol/schema.hpp"

#include "sphfsi/protocol/codec.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace sphfsi::schema {
namespace {
std::string join(const std::string& path, const std::string& name) {
    return path.empty() ? name : path + "." + name;
}
// A markdown table cell: a literal '|' (as in |residual| or |g|) would end the cell, so it is escaped.
std::string table_cell(const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
}
std::string quoted_list(const std::vector<std::string>& xs) {
    std::string out;
    for (std::size_t i = 0; i < xs.size(); ++i) out += (i ? ", \"" : "\"") + xs[i] + "\"";
    return out;
}
std::string describe(const Value& v) {
    if (v.is_string()) return "\"" + protocol::printable(v.as_string()) + "\"";  // the sender's text: escaped
    if (v.is_int()) return std::to_string(v.as_int());
    if (v.is_double()) return number_text(v.as_double());
    if (v.is_bool()) return v.as_bool() ? "true" : "false";
    return v.type_name();
}
}  // namespace

std::string number_text(double x) {
    std::ostringstream s;
    s << x;
    if (std::strtod(s.str().c_str(), nullptr) == x || !std::isfinite(x)) return s.str();
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    return std::string(buf, r.ptr);
}

void Errors::add(const Value* at, std::string message) {
    // A check may quote the scene's own text (a name, a path, a refused string). Escaping every message here,
    // not at each quote, keeps an ESC or a line break from a scene out of the terminal, the log and the ERROR
    // reply, whatever a future check quotes. Escaping is idempotent, so text printable() already escaped stays.
    message = protocol::printable(message, message.size());
    if (at && at->line > 0) message = "line " + std::to_string(at->line) + ": " + message;
    if (at && at->line == Value::kFromOverride) message = "--set: " + message;
    items.push_back(std::move(message));
}

Field::Field(std::string name, Kind kind, std::string doc)
    : name_(std::move(name)), doc_(std::move(doc)), kind_(kind) {}

std::string Field::allowed() const {
    std::string range;
    if (lo_) range += (lo_open_ ? "> " : ">= ") + number_text(*lo_);
    if (hi_) range += (range.empty() ? "" : " and ") + std::string(hi_open_ ? "< " : "<= ") + number_text(*hi_);
    std::string u = unit_.empty() ? "" : " (" + unit_ + ")";
    switch (kind_) {
        case Kind::Number: return "a number" + (range.empty() ? "" : " " + range) + u;
        case Kind::Integer: return "an integer" + (range.empty() ? "" : " " + range) + u;
        case Kind::Boolean: return "true or false";
        case Kind::String: return "a string";
        case Kind::Choice: return "one of " + quoted_list(choices_);
        case Kind::Vector:
            return (length_ ? "an array of " + std::to_string(length_) + " numbers" : std::string("an array of numbers")) +
                   (range.empty() ? "" : ", each " + range) + u;
        case Kind::Table: return "a table";
        case Kind::TableArray: return "an array of tables ([[" + name_ + "]])";
        case Kind::FreeTable: return "a table (checked by the participant)";
    }
    return "";
}

Value Field::validate(const Value& v, const std::string& path, Errors& errors) const {
    auto bad = [&](const std::string& why) {
        errors.add(&v, "key '" + path + "': " + why + "; allowed: " + allowed());
        return v;
    };
    auto in_range = [&](double x) {
        if (!std::isfinite(x)) return false;
        if (lo_ && (lo_open_ ? !(x > *lo_) : !(x >= *lo_))) return false;
        if (hi_ && (hi_open_ ? !(x < *hi_) : !(x <= *hi_))) return false;
        return true;
    };
    switch (kind_) {
        case Kind::Number:
            if (!v.is_number()) return bad("got " + std::string(v.type_name()));
            if (!in_range(v.as_double())) return bad("got " + describe(v));
            return Value(v.as_double());  // ints are accepted where a float is wanted
        case Kind::Integer:
            if (!v.is_int()) return bad("got " + std::string(v.type_name()));
            // The solvers read integer keys into 32-bit ints: a larger value would wrap silently (2^32 + 1
            // read as 1), whatever range the key itself allows.
            if (v.as_int() < std::numeric_limits<std::int32_t>::min() || v.as_int() > std::numeric_limits<std::int32_t>::max())
                return bad("got " + describe(v) + ", beyond the 32-bit range every integer key is read into");
            if (!in_range(static_cast<double>(v.as_int()))) return bad("got " + describe(v));
            return v;
        case Kind::Boolean:
            if (!v.is_bool()) return bad("got " + std::string(v.type_name()));
            return v;
        case Kind::String:
            if (!v.is_string()) return bad("got " + std::string(v.type_name()));
            return v;
        case Kind::Choice:
            if (!v.is_string()) return bad("got " + std::string(v.type_name()));
            for (const auto& c : choices_)
                if (c == v.as_string()) return v;
            return bad("got " + describe(v));
        case Kind::Vector: {
            if (!v.is_array()) return bad("got " + std::string(v.type_name()));
            const auto& a = v.as_array();
            if (length_ && a.size() != length_) return bad("got " + std::to_string(a.size()) + " entries");
            Value::Array out;
            for (const Value& x : a) {
                if (!x.is_number()) return bad("an entry is " + std::string(x.type_name()));
                if (!in_range(x.as_double())) return bad("an entry is " + describe(x));
                out.emplace_back(x.as_double());
            }
            Value r(std::move(out));
            r.line = v.line;
            return r;
        }
        case Kind::Table:
            if (!v.is_table()) return bad("got " + std::string(v.type_name()));
            return table_->validate(v, path, errors);
        case Kind::TableArray: {
            if (!v.is_array()) return bad("got " + std::string(v.type_name()));
            Value::Array out;
            std::size_t i = 0;
            for (const Value& x : v.as_array()) {
                std::string p = path + "[" + std::to_string(i++) + "]";
                if (!x.is_table()) {
                    errors.add(&x, "key '" + p + "': got " + x.type_name() + "; allowed: a table");
                    continue;
                }
                out.push_back(table_->validate(x, p, errors));
            }
            return Value(std::move(out));
        }
        case Kind::FreeTable:
            if (!v.is_table()) return bad("got " + std::string(v.type_name()));
            return v;
    }
    return v;
}

void Field::document(const std::string& prefix, std::string& out) const {
    std::string key = join(prefix, name_);
    if (kind_ == Kind::Table || kind_ == Kind::TableArray) {
        out += table_->document(kind_ == Kind::TableArray ? key + "[]" : key);
        return;
    }
    std::string def = required_ ? "required" : (fallback_ ? describe(*fallback_) : "optional");
    if (fallback_ && fallback_->is_array()) {
        def = "[";
        for (std::size_t i = 0; i < fallback_->as_array().size(); ++i)
            def += (i ? ", " : "") + describe(fallback_->as_array()[i]);
        def += "]";
    }
    out += "| `" + key + "` | " + table_cell(allowed()) + " | " + table_cell(def) + " | " + table_cell(doc_) + " |\n";
}

Field& TableSchema::add(Field f) {
    for (auto& existing : fields_)
        if (existing.name() == f.name()) throw std::logic_error("schema: duplicate key " + f.name());
    fields_.push_back(std::move(f));
    return fields_.back();
}

Field& TableSchema::number(std::string n, std::string d) { return add(Field(std::move(n), Field::Kind::Number, std::move(d))); }
Field& TableSchema::integer(std::string n, std::string d) { return add(Field(std::move(n), Field::Kind::Integer, std::move(d))); }
Field& TableSchema::boolean(std::string n, std::string d) { return add(Field(std::move(n), Field::Kind::Boolean, std::move(d))); }
Field& TableSchema::string(std::string n, std::string d) { return add(Field(std::move(n), Field::Kind::String, std::move(d))); }
Field& TableSchema::choice(std::string n, std::vector<std::string> allowed, std::string d) {
    Field& f = add(Field(std::move(n), Field::Kind::Choice, std::move(d)));
    f.choices_ = std::move(allowed);
    return f;
}
Field& TableSchema::vector(std::string n, std::size_t length, std::string d) {
    Field& f = add(Field(std::move(n), Field::Kind::Vector, std::move(d)));
    f.length_ = length;
    return f;
}
TableSchema& TableSchema::table(std::string n, std::string d, bool req) {
    Field f(std::move(n), Field::Kind::Table, d);
    f.table_ = std::make_shared<TableSchema>(std::move(d));
    f.required_ = req;
    return *add(std::move(f)).table_;
}
TableSchema& TableSchema::table_array(std::string n, std::string d) {
    Field f(std::move(n), Field::Kind::TableArray, d);
    f.table_ = std::make_shared<TableSchema>(std::move(d));
    return *add(std::move(f)).table_;
}
Field& TableSchema::free_table(std::string n, std::string d) {
    return add(Field(std::move(n), Field::Kind::FreeTable, std::move(d)));
}

Value TableSchema::validate(const Value& input, const std::string& path, Errors& errors) const {
    const std::size_t errors_before = errors.items.size();
    Value::Table out;
    if (!input.is_table()) {
        errors.add(&input, "key '" + path + "': got " + input.type_name() + "; allowed: a table");
        return input;
    }
    for (const auto& [key, v] : input.as_table()) {
        bool known = false;
        for (const Field& f : fields_) known = known || f.name() == key;
        if (!known) {
            std::vector<std::string> names;
            for (const Field& f : fields_) names.push_back(f.name());
            // The key is the scene's or the sender's own text: quoted escaped (a control character such as
            // ESC would reach a terminal through the log as it is; a review, 2026-11-27).
            errors.add(&v, "unknown key '" + join(path, protocol::printable(key)) + "'; allowed keys here: " +
                               (names.empty() ? std::string("none") : quoted_list(names)));
        }
    }
    for (const Field& f : fields_) {
        std::string key = join(path, f.name());
        if (const Value* v = input.find(f.name())) {
            Value checked = f.validate(*v, key, errors);
            checked.line = v->line;
            out[f.name()] = std::move(checked);
        } else if (f.is_required()) {
            errors.add(&input, "missing required key '" + key + "'; allowed: " + f.allowed());
        } else if (f.fallback_) {
            out[f.name()] = *f.fallback_;
        }
    }
    Value result(std::move(out));
    result.line = input.line;
    // Cross-key rules only make sense on individually valid keys: they run when this table's own keys and
    // tables are valid, whatever was wrong elsewhere, so that one look at a scene names every mistake (they
    // had waited for the whole scene to be valid until 2026-11-29).
    if (errors.items.size() == errors_before)
        for (const auto& c : checks_) c(result, path, errors);
    return result;
}

std::string TableSchema::document(const std::string& path) const {
    std::string out;
    std::string head = path.empty() ? "(top level)" : "`[" + path + "]`";
    out += "\n#### " + head + "\n\n" + (doc_.empty() ? "" : doc_ + "\n\n");
    out += "| key | allowed | default | meaning |\n|---|---|---|---|\n";
    std::string nested;
    for (const Field& f : fields_) {
        if (f.kind() == Field::Kind::Table || f.kind() == Field::Kind::TableArray)
            f.document(path, nested);
        else
            f.document(path, out);
    }
    return out + nested;
}

void throw_if_any(const Errors& errors, const std::string& source) {
    if (errors.empty()) return;
    std::string msg;
    for (const auto& e : errors.items) msg += source + ": " + e + "\n";
    msg.pop_back();
    throw ConfigError(msg);
}

}  // namespace sphfsi::schema
