// Reading vector elements of a verified FlatBuffers message without assuming
// their alignment: the verifier (FlatBuffers 2.0.8) checks a vector's 4-byte
// length word, not that its doubles or structs lie on 8 bytes, and a foreign
// writer need not put them there (found by fuzzing: tests/fuzz/messages).
#pragma once

#include <flatbuffers/flatbuffers.h>

#include <cstring>
#include <vector>

namespace plr::sim {

template <class T>
T element(const flatbuffers::Vector<T>& v, flatbuffers::uoffset_t i) {
  T x;
  std::memcpy(&x, v.Data() + i * sizeof(T), sizeof(T));
  return flatbuffers::EndianScalar(x);
}

// A struct of a vector of structs, copied out.
template <class S>
S element(const flatbuffers::Vector<const S*>& v, flatbuffers::uoffset_t i) {
  S x;
  std::memcpy(static_cast<void*>(&x), v.Data() + i * sizeof(S), sizeof(S));
  return x;
}

// Every element, copied out.
template <class T>
std::vector<T> elements(const flatbuffers::Vector<T>& v) {
  std::vector<T> out(v.size());
  for (flatbuffers::uoffset_t i = 0; i < v.size(); ++i) out[i] = element(v, i);
  return out;
}

}  // namespace plr::sim
