// ROS 2 rosbag2 sqlite3 storage (.db3; the default storage up to ROS 2 Humble), read with Debian's libsqlite3.
// A bag is a folder: metadata.yaml (rosbag2_bagfile_information: storage_identifier, relative_file_paths,
// compression_mode, compression_format, ...) and one or more NAME_N.db3 files (split by size or duration, in
// that order). Each .db3 has the tables
//   topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, offered_qos_profiles TEXT
//          [, type_description_hash TEXT])   (offered_qos_profiles since Eloquent, the hash since Iron)
//   messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB)  (index timestamp_idx)
// (and schema, metadata, message_definitions in newer ones). rosbag2 reads a file's messages in timestamp order,
// ties by id, and the files one after the other; so does this reader. The data are the CDR bytes MCAP holds.
// Compression: "message" mode (each data blob a zstd frame) is decompressed here; "file" mode (NAME_N.db3.zstd,
// the whole database compressed) is one error saying how to decompress it.
#include <sqlite3.h>
#include <yaml.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fploc/recording/decompress.h"
#include "readers.h"

namespace fploc::rec {
namespace {

namespace fs = std::filesystem;

// What metadata.yaml says, as far as this reader needs it.
struct BagMetadata {
  std::string storage;            // storage_identifier: sqlite3, mcap
  std::vector<std::string> files; // relative_file_paths
  std::string compression_mode;   // "", FILE, MESSAGE
  std::string compression_format; // "", zstd
};

// The scalars and the one list of rosbag2_bagfile_information (libyaml's document API; the whole file is small).
bool parse_metadata(const std::string& text, BagMetadata* md, std::string* why) {
  yaml_parser_t parser;
  yaml_document_t doc;
  if (!yaml_parser_initialize(&parser)) return *why = "cannot initialise the YAML parser", false;
  yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());
  if (!yaml_parser_load(&parser, &doc)) {
    *why = "YAML error at line " + std::to_string(parser.problem_mark.line + 1) + ": " +
           (parser.problem ? parser.problem : "unknown");
    yaml_parser_delete(&parser);
    return false;
  }
  auto scalar = [&](yaml_node_t* n) {
    return n && n->type == YAML_SCALAR_NODE
               ? std::string(reinterpret_cast<const char*>(n->data.scalar.value), n->data.scalar.length)
               : std::string();
  };
  auto find = [&](yaml_node_t* map, const char* key) -> yaml_node_t* {
    if (!map || map->type != YAML_MAPPING_NODE) return nullptr;
    for (auto* p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; ++p)
      if (scalar(yaml_document_get_node(&doc, p->key)) == key) return yaml_document_get_node(&doc, p->value);
    return nullptr;
  };
  bool ok = true;
  yaml_node_t* info = find(yaml_document_get_root_node(&doc), "rosbag2_bagfile_information");
  if (!info) {
    ok = false, *why = "no 'rosbag2_bagfile_information' mapping";
  } else {
    md->storage = scalar(find(info, "storage_identifier"));
    md->compression_mode = scalar(find(info, "compression_mode"));
    md->compression_format = scalar(find(info, "compression_format"));
    yaml_node_t* files = find(info, "relative_file_paths");
    if (files && files->type == YAML_SEQUENCE_NODE)
      for (auto* i = files->data.sequence.items.start; i < files->data.sequence.items.top; ++i)
        md->files.push_back(scalar(yaml_document_get_node(&doc, *i)));
    else
      ok = false, *why = "no 'relative_file_paths' list";
  }
  yaml_document_delete(&doc);
  yaml_parser_delete(&parser);
  return ok;
}

std::string lower(std::string s) {
  for (auto& ch : s) ch = char(std::tolower(uint8_t(ch)));
  return s;
}

// NAME_12.db3 after NAME_9.db3: the split index as a number.
bool split_order(const fs::path& a, const fs::path& b) {
  auto index = [](const fs::path& p) {
    const std::string s = p.stem().string();
    const auto k = s.find_last_of('_');
    long v = -1;
    if (k != std::string::npos && k + 1 < s.size() && std::all_of(s.begin() + long(k) + 1, s.end(), ::isdigit))
      v = std::strtol(s.c_str() + k + 1, nullptr, 10);
    return std::pair{s.substr(0, k == std::string::npos ? s.size() : k), v};
  };
  return index(a) < index(b);
}

bool zstd_magic(const uint8_t* d, size_t n) { return n >= 4 && d[0] == 0x28 && d[1] == 0xB5 && d[2] == 0x2F && d[3] == 0xFD; }

const char* kFileModeHint =
    "rosbag2 'file' compression (the whole .db3 compressed with zstd): decompress it first (`zstd -d FILE.db3.zstd`, or "
    "`ros2 bag decompress` on the bag folder) and import the .db3";

class Db3Reader : public Recording {
 public:
  Db3Reader(std::vector<std::string> files, std::string name, bool message_zstd)
      : files_(std::move(files)), name_(std::move(name)), message_zstd_(message_zstd) {
    format_ = "rosbag2 sqlite3";
    std::error_code ec;
    for (const auto& f : files_) size_ += fs::file_size(f, ec), ec.clear();
  }
  // One database in memory (fuzzing, tests).
  Db3Reader(const uint8_t* data, size_t n, std::string name) : name_(std::move(name)), mem_(data), mem_n_(n) {
    format_ = "rosbag2 sqlite3";
    files_.push_back(name_);
    size_ = n;
  }
  ~Db3Reader() override { close(); }
  // Opens the first file (its tables and topics): false with error() when it cannot be read at all.
  bool start() { return open_next(); }

  bool next(RawMessage& m) override {
    while (!done_) {
      if (!stmt_ && !open_next()) return false;
      if (!stmt_) continue;  // (an empty file list entry: none)
      const int rc = sqlite3_step(stmt_);
      if (rc == SQLITE_ROW) {
        ++rows_;
        const int64_t topic = sqlite3_column_int64(stmt_, 0);
        const auto it = topic_conn_.find(topic);
        const int64_t id = sqlite3_column_int64(stmt_, 3);
        if (it == topic_conn_.end())
          return stop("message id " + std::to_string(id) + " names topic id " + std::to_string(topic) +
                      ", which the topics table does not hold");
        m = RawMessage{};
        m.conn = it->second;
        m.time_ns = sqlite3_column_int64(stmt_, 1);
        m.data = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, 2));
        m.size = size_t(sqlite3_column_bytes(stmt_, 2));
        if (!m.data) m.size = 0;
        m.offset = uint64_t(id);
        m.row = true;
        if (message_zstd_) {
          // "message" compression: each blob one zstd frame; its size from the frame header.
          const unsigned long long n = frame_size(m.data, m.size);  // a few bytes' frame is 14 B: no minimum
          if (n == ~0ULL) return stop("message id " + std::to_string(id) + ": not a zstd frame with its size (the bag says "
                                      "'message' compression with zstd)");
          const std::string e = decompress("zstd", m.data, m.size, size_t(n), buf_);
          if (!e.empty()) return stop("message id " + std::to_string(id) + " (zstd): " + e);
          m.data = buf_.data(), m.size = buf_.size();
        }
        return true;
      }
      if (rc == SQLITE_DONE) {
        done_bytes_ += file_bytes_;
        close();
        continue;
      }
      return stop(sql_error("reading the messages table after " + std::to_string(rows_) +
                            (rows_total_ ? " of " + std::to_string(rows_total_) : std::string()) + " messages"));
    }
    return false;
  }
  uint64_t position() const override {
    if (done_ && !stmt_) return done_bytes_;
    return done_bytes_ + (rows_total_ ? uint64_t(double(file_bytes_) * double(rows_) / double(rows_total_)) : 0);
  }

 private:
  // A zstd frame's content size (~0: unknown, bad, or over 1 GiB).
  static unsigned long long frame_size(const uint8_t* d, size_t n) {
    const unsigned long long s = ZSTD_getFrameContentSize(d, n);
    return s == ZSTD_CONTENTSIZE_ERROR || s == ZSTD_CONTENTSIZE_UNKNOWN || s > (1ULL << 30) ? ~0ULL : s;
  }
  // The file being read (errors name it, not the folder).
  std::string cur_name() const { return file_ > 0 ? files_[file_ - 1] : name_; }
  std::string sql_error(const std::string& doing) {
    const int code = db_ ? sqlite3_extended_errcode(db_) : SQLITE_ERROR;
    std::string what = db_ ? sqlite3_errmsg(db_) : "cannot open";
    if ((code & 0xff) == SQLITE_CORRUPT) what += cut_note_.empty() ? " (the file is damaged)" : cut_note_;
    if ((code & 0xff) == SQLITE_NOTADB) what += " (not an SQLite database, or its header is damaged)";
    return doing + ": sqlite: " + what;
  }
  bool stop(const std::string& what) {
    done_ = true;
    close();
    return fail(cur_name() + ": " + what);
  }
  void close() {
    if (stmt_) sqlite3_finalize(stmt_), stmt_ = nullptr;
    if (db_) sqlite3_close(db_), db_ = nullptr;
  }
  // Opens files_[file_] (the next file), reads its topics and starts the messages query.
  bool open_next() {
    if (file_ >= files_.size()) {
      done_ = true;
      return false;
    }
    const std::string path = files_[file_++];
    rows_ = rows_total_ = 0;
    cut_note_.clear();
    std::error_code ec;
    file_bytes_ = mem_ ? mem_n_ : fs::file_size(path, ec);
    if (!mem_) {
      std::ifstream in(path, std::ios::binary);
      char head[16] = {};
      in.read(head, 16);
      const auto got = size_t(in.gcount());
      if (!in && got == 0 && !fs::exists(path)) return stop("no such file (the bag's metadata.yaml lists it)");
      if (zstd_magic(reinterpret_cast<const uint8_t*>(head), got)) return stop(kFileModeHint);
      if (got == 16 && std::memcmp(head, "SQLite format 3", 16) == 0 && file_bytes_ < 100)
        return stop(std::to_string(file_bytes_) + " B: cut short inside the SQLite header (100 B)");
      if (got < 16 || std::memcmp(head, "SQLite format 3", 16) != 0)
        return stop("not an SQLite database (a rosbag2 .db3 starts with 'SQLite format 3')");
      // The header's page size (bytes 16-17, 1 = 65536) and page count (28-31, big-endian): a file shorter than
      // they say was cut short.
      uint8_t h[32] = {};
      in.clear();
      in.seekg(0);
      in.read(reinterpret_cast<char*>(h), 32);
      const uint64_t page = h[16] << 8 | h[17], pages = uint64_t(h[28]) << 24 | h[29] << 16 | h[30] << 8 | h[31];
      const uint64_t want = (page == 1 ? 65536 : page) * pages;
      cut_note_ = in && want > file_bytes_ ? "; the file is cut short: " + std::to_string(file_bytes_) + " B of the " +
                                                 std::to_string(want) + " B its header gives"
                                           : "";
      if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK)
        return stop(sql_error("opening"));
    } else {
      if (sqlite3_open_v2(":memory:", &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK)
        return stop(sql_error("opening"));
      // The caller's bytes, read-only: sqlite3_deserialize does not write into a READONLY buffer.
      if (sqlite3_deserialize(db_, "main", const_cast<uint8_t*>(mem_), sqlite3_int64(mem_n_), sqlite3_int64(mem_n_),
                              SQLITE_DESERIALIZE_READONLY) != SQLITE_OK)
        return stop(sql_error("opening"));
    }
    sqlite3_limit(db_, SQLITE_LIMIT_LENGTH, 1 << 30);
    // A file cut short (a recorder killed, a copy interrupted) is shorter than its header's page count, which sqlite
    // calls corrupt at once; with writable_schema it takes the file's size instead and reads up to the first missing
    // page, so the messages before the cut are read (the connection is read-only: nothing is written).
    sqlite3_exec(db_, "PRAGMA writable_schema=ON", nullptr, nullptr, nullptr);
    // The tables and the columns this reader needs.
    std::string missing;
    for (const char* t : {"topics", "messages"}) {
      sqlite3_stmt* s = nullptr;
      const std::string q = std::string("SELECT 1 FROM sqlite_master WHERE type='table' AND name='") + t + "'";
      if (sqlite3_prepare_v2(db_, q.c_str(), -1, &s, nullptr) != SQLITE_OK) return stop(sql_error("reading its schema"));
      const int rc = sqlite3_step(s);
      sqlite3_finalize(s);
      if (rc != SQLITE_ROW && rc != SQLITE_DONE) return stop(sql_error("reading its schema"));
      if (rc == SQLITE_DONE) missing += std::string(missing.empty() ? "" : " and ") + "'" + t + "'";
    }
    if (!missing.empty())
      return stop("an SQLite database without the table" + std::string(missing.find(" and ") != std::string::npos ? "s " : " ") + missing +
                  ": not a rosbag2 sqlite3 bag");
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id", -1, &s, nullptr) != SQLITE_OK)
      return stop(sql_error("reading the topics table"));
    topic_conn_.clear();
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      auto text = [&](int col) {
        const auto* p = sqlite3_column_text(s, col);
        return p ? std::string(reinterpret_cast<const char*>(p), size_t(sqlite3_column_bytes(s, col))) : std::string();
      };
      Connection c;
      c.topic = text(1);
      const std::string raw_type = text(2);
      c.type = raw_type;
      if (const auto k = c.type.find("/msg/"); k != std::string::npos) c.type.erase(k, 4);
      const std::string ser = text(3);
      c.encoding = ser == "cdr" ? Encoding::kCdr : Encoding::kOther;
      // One connection per (topic, type, serialization) over all the split files.
      const std::string key = c.topic + '\0' + raw_type + '\0' + ser;
      auto [it, fresh] = conn_of_.emplace(key, uint32_t(conn_of_.size()));
      c.id = it->second;
      if (fresh) conns_[c.id] = c;
      topic_conn_[sqlite3_column_int64(s, 0)] = c.id;
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) return stop(sql_error("reading the topics table"));
    // Progress: the rows of this file (the timestamp index, or the table's b-tree: no blob is read).
    if (sqlite3_prepare_v2(db_, "SELECT count(*) FROM messages", -1, &s, nullptr) != SQLITE_OK)
      return stop(sql_error("counting the messages"));
    rc = sqlite3_step(s);
    // Only for the progress line: a count that fails (an index page beyond a cut) must not stop the rows before it.
    rows_total_ = rc == SQLITE_ROW ? uint64_t(std::max<sqlite3_int64>(0, sqlite3_column_int64(s, 0))) : 0;
    sqlite3_finalize(s);
    // rosbag2's order: timestamp, then id.
    if (sqlite3_prepare_v2(db_, "SELECT topic_id, timestamp, data, id FROM messages ORDER BY timestamp, id", -1, &stmt_,
                           nullptr) != SQLITE_OK)
      return stop(sql_error("reading the messages table"));
    return true;
  }

  std::vector<std::string> files_;
  std::string name_;
  bool message_zstd_ = false;
  const uint8_t* mem_ = nullptr;
  size_t mem_n_ = 0;
  size_t file_ = 0;  // the next file to open
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  bool done_ = false;
  std::map<int64_t, uint32_t> topic_conn_;     // this file's topic id -> connection
  std::map<std::string, uint32_t> conn_of_;    // (topic, type, serialization) -> connection
  uint64_t rows_ = 0, rows_total_ = 0, file_bytes_ = 0, done_bytes_ = 0;
  std::vector<uint8_t> buf_;
  std::string cut_note_;  // "; the file is cut short: ..." when it is shorter than its header says
};

}  // namespace

bool is_zstd_file(const uint8_t* d, size_t n) { return zstd_magic(d, n); }

namespace {
// A reader whose first file opened (tables, topics), else nullptr with its one error.
std::unique_ptr<Recording> started(std::unique_ptr<Db3Reader> r, std::string* err) {
  if (r->start()) return r;
  *err = r->error();
  return nullptr;
}
}  // namespace

std::unique_ptr<Recording> open_db3_memory(const uint8_t* data, size_t size, const std::string& name, std::string* err) {
  return started(std::make_unique<Db3Reader>(data, size, name), err);
}

std::unique_ptr<Recording> open_db3_files(const std::vector<std::string>& files, const std::string& name, std::string* err) {
  return started(std::make_unique<Db3Reader>(files, name, false), err);
}

std::string zstd_file_error(const std::string& name) { return name + ": " + kFileModeHint; }

// A rosbag2 folder: its metadata.yaml's files (or, without one, its .db3 files in split order).
std::unique_ptr<Recording> open_bag_folder(const std::string& dir, std::string* err, size_t read_bytes) {
  const fs::path d(dir);
  const fs::path meta = d / "metadata.yaml";
  std::error_code ec;
  BagMetadata md;
  std::vector<std::string> files;
  if (fs::exists(meta, ec)) {
    std::ifstream in(meta);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string why;
    if (!in || !parse_metadata(ss.str(), &md, &why)) {
      *err = meta.string() + ": " + (in ? why : std::string("cannot read")) + " (a rosbag2 bag's metadata.yaml)";
      return nullptr;
    }
    if (lower(md.compression_mode) == "file") {
      *err = dir + ": " + kFileModeHint + " (metadata.yaml: compression_mode FILE, compression_format " +
             escaped(md.compression_format) + ")";
      return nullptr;
    }
    const bool message_zstd = lower(md.compression_mode) == "message";
    if (message_zstd && lower(md.compression_format) != "zstd") {
      *err = meta.string() + ": compression_format '" + escaped(md.compression_format) + "' is not supported (zstd is)";
      return nullptr;
    }
    if (md.files.empty()) {
      *err = meta.string() + ": relative_file_paths lists no file";
      return nullptr;
    }
    for (const auto& f : md.files) files.push_back((d / f).string());
    if (md.storage == "mcap" || (md.storage.empty() && fs::path(md.files[0]).extension() == ".mcap")) {
      if (files.size() > 1 || message_zstd) {
        *err = dir + ": a rosbag2 bag of " + std::to_string(files.size()) + " MCAP files" +
               (message_zstd ? " with 'message' compression" : "") + ": import each .mcap file";
        return nullptr;
      }
      return open_recording(files[0], err, read_bytes);
    }
    if (!md.storage.empty() && md.storage != "sqlite3") {
      *err = meta.string() + ": storage_identifier '" + escaped(md.storage) + "' is not supported (sqlite3 and mcap are)";
      return nullptr;
    }
    return started(std::make_unique<Db3Reader>(files, dir, message_zstd), err);
  }
  std::vector<fs::path> found;
  bool zst = false;
  for (const auto& e : fs::directory_iterator(d, ec)) {
    const auto& p = e.path();
    if (p.extension() == ".db3") found.push_back(p);
    if (p.extension() == ".zstd" && p.stem().extension() == ".db3") zst = true;
  }
  if (found.empty()) {
    *err = dir + (zst ? ": " + std::string(kFileModeHint)
                      : ": is a directory without metadata.yaml or .db3 files (not a rosbag2 bag folder)");
    return nullptr;
  }
  std::sort(found.begin(), found.end(), split_order);
  for (const auto& p : found) files.push_back(p.string());
  return started(std::make_unique<Db3Reader>(files, dir, false), err);
}

}  // namespace fploc::rec
