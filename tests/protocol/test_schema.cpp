// Scene-section schemas: every kind of mistake is reported with the key and the allowed values.
#include <doctest/doctest.h>

#include "sphfsi/protocol/schema.hpp"

using namespace sphfsi;
using namespace sphfsi::schema;

namespace {
TableSchema example() {
    TableSchema s("example");
    s.number("dp", "spacing").unit("m").greater_than(0).at_most(0.1).required();
    s.integer("layers", "wall layers").at_least(1).at_most(8).fallback(3);
    s.choice("kernel", {"wendland", "cubic"}, "kernel").fallback("wendland");
    s.vector("gravity", 2, "gravity").unit("m/s^2").fallback(Value::Array{0.0, -9.81});
    auto& block = s.table_array("block", "water");
    block.number("width", "w").greater_than(0).required();
    return s;
}

std::string errors_of(const Value& input) {
    Errors e;
    example().validate(input, "fluid", e);
    std::string all;
    for (const auto& x : e.items) all += x + "\n";
    return all;
}

Value table(Value::Table t) { return Value(std::move(t)); }
}  // namespace

TEST_CASE("defaults are filled and ints widen to floats") {
    Errors e;
    example().validate(table({{"dp", Value(std::int64_t{0})}}), "fluid", e);
    CHECK(e.items.size() == 1);  // 0 is out of range (> 0)
    Errors ok;
    const Value good = example().validate(table({{"dp", Value(0.01)}}), "fluid", ok);
    CHECK(ok.items.empty());
    CHECK(good.at("layers").as_int() == 3);
    CHECK(good.at("kernel").as_string() == "wendland");
    CHECK(good.at("gravity").as_doubles()[1] == -9.81);
    // A number written as an integer (TOML's 0 and -10) comes out a float, as the solvers read it.
    const Value widened = example().validate(
        table({{"dp", Value(0.01)}, {"gravity", Value(Value::Array{Value(std::int64_t{0}), Value(std::int64_t{-10})})}}), "fluid", ok);
    CHECK(ok.items.empty());
    CHECK(widened.at("gravity").as_array()[1].is_double());
    CHECK(widened.at("gravity").as_array()[1].as_double() == -10.0);
}

TEST_CASE("each kind of mistake names the key and what is allowed") {
    CHECK(errors_of(table({})).find("missing required key 'fluid.dp'") != std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.5)}})).find("key 'fluid.dp': got 0.5; allowed: a number > 0 and <= 0.1 (m)") !=
          std::string::npos);
    CHECK(errors_of(table({{"dp", Value("small")}})).find("key 'fluid.dp': got a string") != std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.01)}, {"kernal", Value("cubic")}}))
              .find("unknown key 'fluid.kernal'; allowed keys here:") != std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.01)}, {"kernel", Value("gauss")}}))
              .find("allowed: one of \"wendland\", \"cubic\"") != std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.01)}, {"layers", Value(2.5)}})).find("key 'fluid.layers': got a float") !=
          std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.01)}, {"gravity", Value(Value::Array{Value(1.0)})}}))
              .find("got 1 entries") != std::string::npos);
    CHECK(errors_of(table({{"dp", Value(0.01)}, {"block", Value(Value::Array{table({})})}}))
              .find("missing required key 'fluid.block[0].width'") != std::string::npos);
}

TEST_CASE("every collected message is escaped, whatever a check quoted, and only once") {
    // A check may quote scene text raw (the watchpoint-name rule did): Errors::add escapes control characters
    // and bytes that are not UTF-8, and leaves text that was escaped already, UTF-8 and backslashes as they are.
    Errors e;
    e.add(nullptr, std::string("got \"tip\x1b[2J\xff\"; allowed: \xe2\x89\xa4 50, \\x1b stays"));
    REQUIRE(e.items.size() == 1);
    CHECK(e.items[0] == "got \"tip\\x1b[2J\\xff\"; allowed: \xe2\x89\xa4 50, \\x1b stays");
}

TEST_CASE("line numbers are reported when known") {
    Value dp(0.5);
    dp.line = 12;
    CHECK(errors_of(table({{"dp", dp}})).rfind("line 12: key 'fluid.dp'", 0) == 0);
}

TEST_CASE("cross-key checks run only on individually valid tables") {
    TableSchema s;
    s.number("a", "").required();
    s.number("b", "").required();
    s.check([](const Value& t, const std::string& path, Errors& e) {
        if (t.at("a").as_double() > t.at("b").as_double()) e.add(&t, path + ": a must not exceed b");
    });
    Errors e;
    s.validate(table({{"a", Value(2.0)}, {"b", Value(1.0)}}), "x", e);
    REQUIRE(e.items.size() == 1);
    CHECK(e.items[0] == "x: a must not exceed b");
    Errors e2;
    s.validate(table({{"a", Value(2.0)}}), "x", e2);
    CHECK(e2.items.size() == 1);  // only the missing key, no crash in the check
}

TEST_CASE("a table's cross-key checks run whatever is wrong in another table") {
    // A scene with a mistake in one section and a broken cross-key rule in another gets both named at once
    // (until 2026-11-29 any earlier mistake in the scene held every later table's rules back).
    TableSchema scene;
    TableSchema& first = scene.table("first", "");
    first.number("n", "").at_least(0).required();
    TableSchema& second = scene.table("second", "");
    second.number("a", "").required();
    second.number("b", "").required();
    second.check([](const Value& t, const std::string& path, Errors& e) {
        if (t.at("a").as_double() > t.at("b").as_double()) e.add(&t, path + ": a must not exceed b");
    });
    Errors e;
    scene.validate(table({{"first", table({{"n", Value(-1.0)}})},
                          {"second", table({{"a", Value(2.0)}, {"b", Value(1.0)}})}}),
                   "", e);
    REQUIRE(e.items.size() == 2);
    CHECK(e.items[0].find("key 'first.n'") != std::string::npos);
    CHECK(e.items[1] == "second: a must not exceed b");
}

TEST_CASE("the reference documents every key") {
    std::string doc = example().document("fluid");
    for (const char* key : {"`fluid.dp`", "`fluid.layers`", "`fluid.kernel`", "`fluid.gravity`", "`fluid.block[].width`"})
        CHECK(doc.find(key) != std::string::npos);
}

TEST_CASE("a '|' in a key's description does not split its row of the markdown table") {
    TableSchema s;
    s.number("tol", "converged when |r| <= tol |x|").fallback(1.0);
    const std::string doc = s.document("c");
    const std::string row = doc.substr(doc.find("| `c.tol`"));
    CHECK(row.find("converged when \\|r\\| <= tol \\|x\\|") != std::string::npos);
    // Four cells: the row's unescaped bars are its five borders.
    int bars = 0;
    for (std::size_t i = 0; i < row.find('\n'); ++i)
        if (row[i] == '|' && (i == 0 || row[i - 1] != '\\')) ++bars;
    CHECK(bars == 5);
}

TEST_CASE("dotted paths reach into tables and arrays of tables") {
    Value root;
    set_path(root, "fluid.dp", Value(0.01));
    set_path(root, "structure.members", Value(Value::Array{table({{"n", Value(3)}}), table({{"n", Value(4)}})}));
    set_path(root, "structure.members[1].n", Value(9));
    CHECK(find_path(root, "fluid.dp")->as_double() == 0.01);
    CHECK(find_path(root, "structure.members[1].n")->as_int() == 9);
    CHECK(find_path(root, "structure.members[0].n")->as_int() == 3);
    CHECK(find_path(root, "structure.members[5].n") == nullptr);
    // An entry is changed, never added: the error says which entries there are, or that there is no array.
    CHECK_THROWS_WITH_AS(set_path(root, "structure.members[5].n", Value(1)),
                         doctest::Contains("'structure.members' has 2 entries, structure.members[0] to structure.members[1]"),
                         ConfigError);
    CHECK_THROWS_WITH_AS(set_path(root, "structure.loads[0].n", Value(1)),
                         doctest::Contains("there is no 'structure.loads' to take entry 0 of"), ConfigError);
    CHECK_THROWS_WITH_AS(set_path(root, "fluid.dp[0]", Value(1)),
                         doctest::Contains("'fluid.dp' is a float, not an array to take entry 0 of"), ConfigError);
    set_path(root, "structure.none", Value(Value::Array{}));
    CHECK_THROWS_WITH_AS(set_path(root, "structure.none[0].n", Value(1)),
                         doctest::Contains("'structure.none' has no entries"), ConfigError);
    CHECK_THROWS_AS(set_path(root, "structure.members[x].n", Value(1)), ConfigError);
    // An index too large for any array, and an array addressed as a table, are named (both used to escape
    // as std::out_of_range from std::stol, or as a type error that named no key).
    CHECK_THROWS_WITH_AS(set_path(root, "structure.members[99999999999999999999999].n", Value(1)),
                         doctest::Contains("index 99999999999999999999999 is out of range"), ConfigError);
    CHECK_THROWS_WITH_AS(set_path(root, "structure.members.0.n", Value(1)),
                         doctest::Contains("'structure.members' is an array; address an entry as structure.members[INDEX]"),
                         ConfigError);
}
