// The one YAML idiom (core/io/yaml_fields.hpp) on a small struct: a field list drives parse, emit and equality;
// nested sections, enum words, lists, paths and required keys; every error names file:line and the dotted field.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/io/yaml_fields.hpp"

namespace rotolidar {
namespace {

enum class Shape { kRound, kSquare };
const yaml::EnumWordList<Shape>& EnumWords(Shape*) {
  static const yaml::EnumWordList<Shape> words{{"round", Shape::kRound}, {"square", Shape::kSquare}};
  return words;
}

struct Inner {
  double size_m = 1.0;
  Shape shape = Shape::kRound;
  std::vector<int> ids;
};

struct Outer {
  int count = 2;
  std::string name = "x";
  Inner inner;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  std::string file;
};

template <class V>
void Visit(V& v, Inner& c) {
  v("size_m", yaml::Required(&c.size_m)), v("shape", &c.shape), v("ids", &c.ids);
}

template <class V>
void Visit(V& v, Outer& c) {
  v("count", &c.count), v("name", &c.name), v("inner", &c.inner), v("point", &c.point);
  v("file", yaml::EmitIf(!c.file.empty(), yaml::Path(&c.file)));
}

std::string Emit(const Outer& c) {
  YAML::Emitter out;
  yaml::Emit(out, c);
  return out.c_str();
}

/// Parses `text` (as the file /cfg/t.yaml, section "top") over the defaults; returns the error ("" if none).
std::string ParseError(const std::string& text, Outer* c) {
  try {
    yaml::Parse(yaml::Section("/cfg/t.yaml", "top"), YAML::Load(text), c);
  } catch (const yaml::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlFields, EmitParseRoundTripInListOrder) {
  Outer c;
  c.count = 5;
  c.inner = {0.25, Shape::kSquare, {3, 4}};
  c.point = Eigen::Vector3d(1, 2, 3);
  const std::string text = Emit(c);
  EXPECT_EQ(text,
            "count: 5\nname: x\ninner:\n  size_m: 0.25\n  shape: square\n  ids: [3, 4]\npoint: [1, 2, 3]");
  Outer back;
  ASSERT_EQ(ParseError(text, &back), "");
  EXPECT_TRUE(yaml::Equal(back, c));
  back.inner.ids.push_back(5);  // a nested field counts
  EXPECT_FALSE(yaml::Equal(back, c));
  // Absent keys keep their values; a relative path resolves against the file's folder and is then written.
  Outer partial;
  ASSERT_EQ(ParseError("inner: {size_m: 2}\nfile: ../data/f.csv\n", &partial), "");
  EXPECT_EQ(partial.count, 2);
  EXPECT_EQ(partial.inner.shape, Shape::kRound);
  EXPECT_EQ(partial.file, "/data/f.csv");
  EXPECT_NE(Emit(partial).find("file: /data/f.csv"), std::string::npos);
}

TEST(YamlFields, ErrorsNameFileLineAndDottedField) {
  Outer c;
  struct Case {
    std::string text, where, what;
  };
  const std::vector<Case> cases = {
      {"count: 1\ninner:\n  size_m: 1\n  colour: red\n", "/cfg/t.yaml:4:", "unknown key 'colour' in top.inner"},
      {"inner:\n  size_m: 1\n  shape: oval\n", "/cfg/t.yaml:3:",
       "field 'top.inner.shape': unknown value 'oval' (one of: round, square)"},
      {"inner:\n  size_m: 1\n  ids:\n    - 1\n    - two\n", "/cfg/t.yaml:5:", "field 'top.inner.ids': cannot read"},
      {"inner:\n  shape: square\n", "/cfg/t.yaml:2:", "missing required key 'size_m' in top.inner"},
      {"point: [1, 2]\n", "/cfg/t.yaml:1:", "field 'top.point': expected 3 numbers"},
      {"inner: 3\n", "/cfg/t.yaml:1:", "top.inner: expected a mapping"},
      // A key that is itself a mapping is legal YAML (found by fuzzing: it once escaped as an exception).
      {"count: 1\n{etd: 6}: b\n", "/cfg/t.yaml:2:", "top: a key must be a plain name, not a mapping"},
      {"inner:\n  [1, 2]: b\n", "/cfg/t.yaml:2:", "top.inner: a key must be a plain name, not a list"},
  };
  for (const Case& k : cases) {
    const std::string e = ParseError(k.text, &c);
    EXPECT_NE(e.find(k.where), std::string::npos) << e;
    EXPECT_NE(e.find(k.what), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace rotolidar
