// The two readers behind open_recording() (internal).
#pragma once
#include <vector>

#include "fploc/recording/recording.h"

namespace fploc::rec {

// ROS 1 bag format 2.0, read sequentially (the index at the end is not needed: an unindexed bag or one
// cut short by a crash reads up to its last whole record). Chunks: none, bz2, lz4.
class BagReader : public Recording {
 public:
  BagReader(std::unique_ptr<FileBytes> f, std::string name);
  bool next(RawMessage& m) override;
  uint64_t position() const override { return pos_; }

 private:
  bool stop(const std::string& what);
  std::unique_ptr<FileBytes> f_;
  std::string name_;
  size_t pos_ = 0;
  bool done_ = false;
  // The chunk being read.
  const uint8_t* cd_ = nullptr;
  size_t cn_ = 0, cpos_ = 0, chunk_at_ = 0;
  std::string chunk_what_;
  std::vector<uint8_t> buf_;
};

// MCAP (data section in file order: chunks none/zstd/lz4, or messages outside chunks; the summary
// section and indexes are not needed).
class McapReader : public Recording {
 public:
  McapReader(std::unique_ptr<FileBytes> f, std::string name);
  bool next(RawMessage& m) override;
  uint64_t position() const override { return pos_; }

 private:
  bool stop(const std::string& what);
  // One record's content (opcode and body); false with *why on a bad record.
  bool on_record(uint8_t op, const uint8_t* b, size_t n, RawMessage* m, bool* is_message, std::string* why);
  std::unique_ptr<FileBytes> f_;
  std::string name_;
  size_t pos_ = 0;
  bool done_ = false;
  const uint8_t* cd_ = nullptr;
  size_t cn_ = 0, cpos_ = 0, chunk_at_ = 0;
  std::string chunk_what_;
  std::vector<uint8_t> buf_;
  std::map<uint16_t, std::pair<std::string, std::string>> schemas_;  // id -> (name, encoding)
};

}  // namespace fploc::rec
