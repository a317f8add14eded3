// The file.* operations of the domain's FileManager: how a node fetches the files of a package
// (protocol/package.hpp) it lacks. A file is asked for by its content hash, never by a path: the
// domain serves only what it put into a package it sent.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "protocol/codec.hpp"

namespace rsca::protocol::file {

// At most this much of a file travels in one reply (one DDS sample, fragmented by Cyclone); a
// node asks for several pieces at once.
inline constexpr std::uint64_t kMaxReadBytes = 1ULL << 20U;
inline constexpr std::size_t kMaxLaunchLength = 256; // of ReadRequest::launch
// The one compression of a piece: a zstd frame (content/zstd.hpp), with its content size and
// checksum. The node asks for it; the domain uses it when the frame is smaller than the piece.
inline constexpr std::string_view kZstd = "zstd";

struct ReadRequest {
  std::string sha256;
  std::uint64_t offset = 0;
  std::uint64_t length = 0;               // at most kMaxReadBytes
  std::optional<std::string> launch;      // the launch it is for: its progress counts the bytes
  std::optional<std::string> compression; // kZstd: the node takes the piece compressed
  static constexpr auto fields() {
    using R = ReadRequest;
    return std::tuple{required("sha256", &R::sha256), required("offset", &R::offset),
                      required("length", &R::length), optional("launch", &R::launch),
                      optional("compression", &R::compression)};
  }
};

struct ReadReply {
  // The bytes from offset: `length` of them, fewer at the end. They travel beside the reply's
  // JSON (codec.hpp, kPayloadField), absent when there are none.
  std::optional<Bytes> payload;
  std::uint64_t size = 0; // the whole file's
  // kZstd: the payload is one zstd frame of the piece; absent: the piece's bytes as they are.
  std::optional<std::string> compression;
  static constexpr auto fields() {
    return std::tuple{optional(kPayloadField, &ReadReply::payload),
                      required("size", &ReadReply::size),
                      optional("compression", &ReadReply::compression)};
  }
};

// What a launch's nodes fetched for it: the files' bytes, and the bytes that travelled.
struct Delivered {
  std::uint64_t bytes = 0;
  std::uint64_t wire_bytes = 0;
};

struct Read {
  static constexpr std::string_view name = "file.read";
  using Request = ReadRequest;
  using Reply = ReadReply;
};

} // namespace rsca::protocol::file
