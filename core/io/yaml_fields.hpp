#pragma once
// The project's one YAML idiom: every config struct lists its fields once, as (key, field) pairs, in one
// template function declared in the struct's own namespace (so argument-dependent lookup finds it):
//
//   template <class V>
//   void Visit(V& v, CameraConfig& c) { v("enabled", &c.enabled), v("rate_hz", &c.rate_hz), ...; }
//
// The generic visitors below drive everything from that list: Parse (strict keys, then every present key read
// over the current values), Emit (every field, in list order) and Equal (field-wise ==), so adding a field is
// one edit. Every message names file:line and the dotted field ("camera.renderer"). Parsers throw ParseError
// (yaml_util.hpp); public functions catch it at their boundary and return a Status.
//
// A field (the second argument of v) is a pointer to
//   - a scalar or std::string (yaml-cpp's as<T>), or a std::vector of fields (a list, read item by item);
//   - an enum E that provides `const std::vector<std::pair<const char*, E>>& EnumWords(E*)` in its namespace
//     (written as those words; an unknown word is an error listing them);
//   - Eigen::Vector3d or std::array<double, N> (a list of exactly 3 / N numbers), Pose3 (GetPose's layout);
//   - a struct with its own Visit: a nested section (a mapping, checked, read and written recursively);
// or one of the wrappers: Custom (the owner's read/write functions), EmitIf (written only when a condition
// holds), Path (a file path, resolved against the YAML file's folder), Required (an error when missing),
// Fixed (a key whose only allowed value is a given word).
//
// Define each struct's Visit exactly once in the program (in the file that owns its YAML), before the first
// Parse/Emit/Equal of any struct that contains it.
#include <array>
#include <filesystem>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "core/io/yaml_util.hpp"

namespace rotolidar::yaml {

// ---- where a mapping sits (for messages) ----

/// A mapping being read: its file and the dotted path of its keys.
struct Section {
  explicit Section(std::string file_, std::string path_ = "", std::string label_ = "")
      : file(std::move(file_)), path(std::move(path_)), label(std::move(label_)) {}
  std::string file;
  std::string path;   ///< e.g. "motor.profile"; "" at a file's top level
  std::string label;  ///< names the top level in messages (e.g. "sim"); unused below it

  std::string Field(const std::string& key) const { return path.empty() ? key : path + "." + key; }
  std::string Name() const { return path.empty() ? label : path; }
  Section Child(const std::string& key) const { return Section(file, Field(key), label); }
};

// ---- enums as words ----

template <class E>
using EnumWordList = std::vector<std::pair<const char*, E>>;

/// E's word table (EnumWords(E*) found by argument-dependent lookup).
template <class E>
const EnumWordList<E>& WordsOf() {
  return EnumWords(static_cast<E*>(nullptr));
}

/// The word of `value`; "unknown" for a value outside the table.
template <class E>
const char* EnumWord(E value) {
  for (const auto& [word, v] : WordsOf<E>())
    if (v == value) return word;
  return "unknown";
}

/// Sets *value to the enum named `word`; false (and *value untouched) for any other word.
template <class E>
bool EnumFromWord(const std::string& word, E* value) {
  for (const auto& [w, v] : WordsOf<E>())
    if (word == w) return *value = v, true;
  return false;
}

/// "a, b, c": the allowed words, for messages.
template <class E>
std::string EnumWordsText() {
  std::string text;
  for (const auto& entry : WordsOf<E>()) text += (text.empty() ? "" : ", ") + std::string(entry.first);
  return text;
}

// ---- wrappers ----

/// Read by parse(const Section& field, const YAML::Node& value, T*) (which throws ParseError or returns a
/// Status), written by emit(YAML::Emitter&, const T&) (the value only; the key is written for it).
template <class T, class P, class E>
struct CustomField {
  T* value;
  P parse;
  E emit;
};
struct NoEmit {};  ///< a Custom field of a parse-only config (never emitted)
template <class T, class P, class E = NoEmit>
CustomField<T, P, E> Custom(T* value, P parse, E emit = {}) {
  return {value, parse, emit};
}

/// Parsed and compared as `field` (a pointer or another wrapper); emitted only when `emit` is true.
template <class F>
struct EmitIfField {
  bool emit;
  F field;
};
template <class F>
EmitIfField<F> EmitIf(bool emit, F field) {
  return {emit, field};
}

/// A file path: a relative path read from the file resolves against the file's folder (lexically normal).
struct PathField {
  std::string* value;
};
inline PathField Path(std::string* value) { return {value}; }

/// `field` (a pointer or another wrapper), and an error naming the key and the section when the key is missing.
template <class F>
struct RequiredField {
  F field;
};
template <class F>
RequiredField<F> Required(F field) {
  return {field};
}

/// A key whose only allowed value is `word` (e.g. a model name); emitted as that word.
struct FixedField {
  const char* word;
};
inline FixedField Fixed(const char* word) { return {word}; }

// ---- sections: types with a Visit ----

/// Collects the keys a Visit lists.
struct KeyCollector {
  std::set<std::string> keys;
  template <class F>
  void operator()(const char* key, const F&) {
    keys.insert(key);
  }
};

template <class T, class = void>
struct HasVisit : std::false_type {};
template <class T>
struct HasVisit<T, std::void_t<decltype(Visit(std::declval<KeyCollector&>(), std::declval<T&>()))>>
    : std::true_type {};

/// The keys S's Visit lists.
template <class S>
std::set<std::string> Keys(S s = S{}) {
  KeyCollector keys;
  Visit(keys, s);
  return keys.keys;
}

template <class S>
void ReadFields(const Section& at, const YAML::Node& node, S* s);

// ---- reading one value ----

template <class T>
struct IsVector : std::false_type {};
template <class T, class A>
struct IsVector<std::vector<T, A>> : std::true_type {};
template <class T>
struct IsArray : std::false_type {};
template <class T, size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};

[[noreturn]] inline void Fail(const std::string& file, const YAML::Node& at, const std::string& what) {
  throw ParseError(Where(file, at) + what);
}

/// A list of exactly n numbers, for Vector3d and std::array fields.
inline std::vector<double> ReadNumbers(const std::string& file, const YAML::Node& node, const std::string& field,
                                       size_t n) {
  std::vector<double> v;
  ReadAs(file, node, field, &v);
  if (v.size() != n) Fail(file, node, "field '" + field + "': expected " + std::to_string(n) + " numbers");
  return v;
}

/// Reads `node` (the value of `at.path`) into *value; messages name file:line and the field.
template <class T>
void ReadValue(const Section& at, const YAML::Node& node, T* value) {
  if constexpr (HasVisit<T>::value) {
    CheckKeys(at.file, node, Keys(*value), at.Name());
    ReadFields(at, node, value);
  } else if constexpr (std::is_enum_v<T>) {
    std::string word;
    ReadAs(at.file, node, at.path, &word);
    if (!EnumFromWord(word, value))
      Fail(at.file, node, "field '" + at.path + "': unknown value '" + word + "' (one of: " + EnumWordsText<T>() +
                              ")");
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    const std::vector<double> v = ReadNumbers(at.file, node, at.path, 3);
    *value = Eigen::Vector3d(v[0], v[1], v[2]);
  } else if constexpr (IsArray<T>::value) {
    const std::vector<double> v = ReadNumbers(at.file, node, at.path, std::tuple_size<T>::value);
    std::copy(v.begin(), v.end(), value->begin());
  } else if constexpr (std::is_same_v<T, Pose3>) {
    ReadPose(at.file, node, at.path, value);
  } else if constexpr (IsVector<T>::value && !std::is_same_v<T, std::vector<bool>>) {
    if (!node.IsSequence()) Fail(at.file, node, "field '" + at.path + "': expected a list");
    T items;
    for (const YAML::Node& item : node) ReadValue(at, item, &items.emplace_back());
    *value = std::move(items);
  } else {
    ReadAs(at.file, node, at.path, value);
  }
}

/// Visits a mapping's fields, reading each key present in `node` (absent keys keep their values).
struct Parser {
  const Section& at;
  const YAML::Node& node;

  template <class T>
  void operator()(const char* key, T* value) {
    if (const YAML::Node child = node[key]) ReadValue(at.Child(key), child, value);
  }
  template <class T, class P, class E>
  void operator()(const char* key, const CustomField<T, P, E>& f) {
    const YAML::Node child = node[key];
    if (!child) return;
    if constexpr (std::is_same_v<decltype(f.parse(at, child, f.value)), Status>) {
      if (Status s = f.parse(at.Child(key), child, f.value); !s) throw ParseError(s.message);
    } else {
      f.parse(at.Child(key), child, f.value);
    }
  }
  template <class F>
  void operator()(const char* key, const EmitIfField<F>& f) {
    (*this)(key, f.field);
  }
  void operator()(const char* key, const PathField& f) {
    const YAML::Node child = node[key];
    if (!child) return;
    ReadAs(at.file, child, at.Field(key), f.value);
    const std::filesystem::path p(*f.value), dir = std::filesystem::path(at.file).parent_path();
    if (!f.value->empty() && p.is_relative() && !dir.empty()) *f.value = (dir / p).lexically_normal().string();
  }
  template <class F>
  void operator()(const char* key, const RequiredField<F>& f) {
    if (!node[key]) Fail(at.file, node, "missing required key '" + std::string(key) + "' in " + at.Name());
    (*this)(key, f.field);
  }
  void operator()(const char* key, const FixedField& f) {
    const YAML::Node child = node[key];
    if (!child) return;
    std::string word;
    ReadAs(at.file, child, at.Field(key), &word);
    if (word != f.word)
      Fail(at.file, child, "field '" + at.Field(key) + "': only '" + f.word + "' is supported, got '" + word + "'");
  }
};

/// Reads every key S's Visit lists that `node` holds (no key check: see Parse).
template <class S>
void ReadFields(const Section& at, const YAML::Node& node, S* s) {
  Parser parse{at, node};
  Visit(parse, *s);
}

/// Strict parse of a mapping: any key not in S's Visit list (nor in `extra_keys`, keys the caller reads
/// itself) is an error, as is a non-mapping; then every present key is read over *s's values.
template <class S>
void Parse(const Section& at, const YAML::Node& node, S* s, const std::set<std::string>& extra_keys = {}) {
  std::set<std::string> keys = Keys(*s);
  keys.insert(extra_keys.begin(), extra_keys.end());
  CheckKeys(at.file, node, keys, at.Name());
  ReadFields(at, node, s);
}

// ---- writing ----

struct Emitter;

template <class T>
void EmitValue(YAML::Emitter& out, const T& value);

/// Visits a mapping's fields, writing each as key: value.
struct Emitter {
  YAML::Emitter& out;

  template <class T>
  void operator()(const char* key, T* value) {
    out << YAML::Key << key << YAML::Value;
    EmitValue(out, *value);
  }
  template <class T, class P, class E>
  void operator()(const char* key, const CustomField<T, P, E>& f) {
    static_assert(!std::is_same_v<E, NoEmit>, "this Custom field has no emit function");
    out << YAML::Key << key << YAML::Value;
    f.emit(out, *f.value);
  }
  template <class F>
  void operator()(const char* key, const EmitIfField<F>& f) {
    if (f.emit) (*this)(key, f.field);
  }
  void operator()(const char* key, const PathField& f) { (*this)(key, f.value); }
  template <class F>
  void operator()(const char* key, const RequiredField<F>& f) {
    (*this)(key, f.field);
  }
  void operator()(const char* key, const FixedField& f) { out << YAML::Key << key << YAML::Value << f.word; }
};

template <class T>
void EmitValue(YAML::Emitter& out, const T& value) {
  if constexpr (HasVisit<T>::value) {
    T copy = value;  // Visit takes non-const fields; the emitter only reads them
    Emitter emit{out};
    out << YAML::BeginMap;
    Visit(emit, copy);
    out << YAML::EndMap;
  } else if constexpr (std::is_enum_v<T>) {
    out << EnumWord(value);
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    out << YAML::Flow << std::vector<double>{value.x(), value.y(), value.z()};
  } else if constexpr (IsArray<T>::value) {
    out << YAML::Flow << std::vector<double>(value.begin(), value.end());
  } else if constexpr (std::is_same_v<T, Pose3>) {
    EmitPoseValue(out, value);
  } else if constexpr (IsVector<T>::value && !std::is_same_v<T, std::vector<bool>>) {
    out << YAML::Flow << YAML::BeginSeq;
    for (const auto& item : value) EmitValue(out, item);
    out << YAML::EndSeq;
  } else {
    out << value;
  }
}

/// Writes every field of s (a struct with a Visit) as one mapping, in its Visit's order.
template <class S>
void Emit(YAML::Emitter& out, const S& s) {
  static_assert(HasVisit<S>::value, "Emit needs a Visit for S");
  EmitValue(out, s);
}

// ---- comparing ----

/// Records (address, comparison) of every field, sections flattened, for Equal.
struct FieldRecorder {
  struct Entry {
    const void* value;
    bool (*equal)(const void*, const void*);
  };
  std::vector<Entry> fields;

  template <class T>
  static bool EqualAs(const void* a, const void* b) {
    return *static_cast<const T*>(a) == *static_cast<const T*>(b);
  }
  template <class T>
  void operator()(const char*, T* value) {
    if constexpr (HasVisit<T>::value) Visit(*this, *value);
    else fields.push_back({value, &EqualAs<T>});
  }
  template <class T, class P, class E>
  void operator()(const char* key, const CustomField<T, P, E>& f) {
    (*this)(key, f.value);
  }
  template <class F>
  void operator()(const char* key, const EmitIfField<F>& f) {
    (*this)(key, f.field);
  }
  void operator()(const char* key, const PathField& f) { (*this)(key, f.value); }
  template <class F>
  void operator()(const char* key, const RequiredField<F>& f) {
    (*this)(key, f.field);
  }
  void operator()(const char*, const FixedField&) {}
};

/// Field-wise equality (operator== of every field Visit lists, sections included).
template <class S>
bool Equal(const S& a, const S& b) {
  S ca = a, cb = b;  // Visit takes non-const fields; only their addresses are recorded
  FieldRecorder ra, rb;
  Visit(ra, ca);
  Visit(rb, cb);
  if (ra.fields.size() != rb.fields.size()) return false;
  for (size_t i = 0; i < ra.fields.size(); ++i)
    if (!ra.fields[i].equal(ra.fields[i].value, rb.fields[i].value)) return false;
  return true;
}

}  // namespace rotolidar::yaml
