// rosbag2 reader: a bag folder (metadata.yaml, its storage's files) or one sqlite3 .db3 file
// (tables topics(id, name, type, serialization_format, ...) and messages(id, topic_id,
// timestamp, data)). A folder whose storage is MCAP is read by the MCAP reader.
#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <utility>

#include "log_reader.hpp"

namespace cs::logio {
namespace {

namespace fs = std::filesystem;

// One database file, its connection closed with it: also when the reader's constructor
// throws part-way (a second file missing, a damaged topics table), where no destructor of
// the reader runs.
struct Db {
  sqlite3* db = nullptr;
  std::string path;
  std::map<int64_t, uint32_t> topics;  // topic id -> channel index

  Db() = default;
  Db(Db&& other) noexcept
      : db(std::exchange(other.db, nullptr)), path(std::move(other.path)), topics(std::move(other.topics)) {}
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;
  Db& operator=(Db&&) = delete;
  ~Db() {
    if (db) sqlite3_close_v2(db);  // sqlite3_open_v2 makes a handle to close even when it fails
  }
};

class Statement {
 public:
  Statement(const Db& db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db.db, sql, -1, &stmt_, nullptr) != SQLITE_OK) fail("cannot query");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() const { return stmt_; }
  [[noreturn]] void fail(const char* what) const {
    throw Error("rosbag2 database '" + db_.path + "': " + what + " (" + shown(sqlite3_errmsg(db_.db), 120) + ")");
  }

 private:
  const Db& db_;
  sqlite3_stmt* stmt_ = nullptr;
};

std::string column(sqlite3_stmt* s, int i) {
  const unsigned char* t = sqlite3_column_text(s, i);
  return t ? reinterpret_cast<const char*>(t) : "";
}

class SqliteReader : public Reader {
 public:
  explicit SqliteReader(const std::string& path, const std::vector<std::string>& files) {
    path_ = path;
    for (const std::string& f : files) open(f);
  }

  std::string format() const override {
    return "rosbag2 sqlite3" + (dbs_.size() > 1 ? ", " + std::to_string(dbs_.size()) + " files" : std::string());
  }

  void scan(const std::vector<bool>& wanted, const Visit& visit) override {
    for (size_t d = 0; d < dbs_.size(); ++d) {
      Statement s(dbs_[d], "SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
      uint64_t rows = 0;
      int rc;
      while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
        ++rows;
        const auto topic = dbs_[d].topics.find(sqlite3_column_int64(s.get(), 1));
        if (topic == dbs_[d].topics.end()) s.fail("a message of a topic the topics table lacks");
        const int64_t t = sqlite3_column_int64(s.get(), 2);
        Channel& c = channels_[topic->second];
        if (!c.count || t < c.firstNs) c.firstNs = t;
        if (!c.count || t > c.lastNs) c.lastNs = t;
        ++c.count;
        if (!wanted.empty() && !wanted[topic->second]) continue;
        const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(s.get(), 3));
        const size_t size = size_t(sqlite3_column_bytes(s.get(), 3));
        visit(MessageRef{topic->second, t, d, uint64_t(sqlite3_column_int64(s.get(), 0)), size}, data, size);
      }
      if (rc == SQLITE_DONE) continue;
      // A damaged file (a recorder's power loss): what was read stands, and the cut is said.
      if (rows == 0) s.fail("cannot read its messages");
      cut_ = "rosbag2 database '" + dbs_[d].path + "' is damaged after " + std::to_string(rows) + " messages (" +
             shown(sqlite3_errmsg(dbs_[d].db), 80) + "): read up to there";
      return;
    }
  }

  void read(const MessageRef& ref, const Use& use) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    const Db& db = dbs_.at(ref.chunk);
    Statement s(db, "SELECT data FROM messages WHERE id = ?");
    sqlite3_bind_int64(s.get(), 1, int64_t(ref.offset));
    if (sqlite3_step(s.get()) != SQLITE_ROW) s.fail(("message row " + std::to_string(ref.offset) + " is gone").c_str());
    use(static_cast<const uint8_t*>(sqlite3_column_blob(s.get(), 0)), size_t(sqlite3_column_bytes(s.get(), 0)));
  }

 private:
  void open(const std::string& file) {
    if (!fs::is_regular_file(file)) throw Error("rosbag2 database '" + file + "' does not exist");
    Db& db = dbs_.emplace_back();
    db.path = file;
    const int rc = sqlite3_open_v2(file.c_str(), &db.db, SQLITE_OPEN_READONLY, nullptr);
    if (rc != SQLITE_OK)
      throw Error("cannot open rosbag2 database '" + file + "': " + shown(sqlite3_errmsg(db.db), 120));
    Statement s(dbs_.back(), "SELECT id, name, type, serialization_format FROM topics");
    int step;
    while ((step = sqlite3_step(s.get())) == SQLITE_ROW) {
      const std::string name = column(s.get(), 1);
      auto it = byName_.find(name);
      if (it == byName_.end()) {
        it = byName_.emplace(name, uint32_t(channels_.size())).first;
        channels_.push_back(Channel{name, column(s.get(), 2), column(s.get(), 3)});
      }
      dbs_.back().topics[sqlite3_column_int64(s.get(), 0)] = it->second;
    }
    if (step != SQLITE_DONE) s.fail("cannot read its topics table");
  }

  std::vector<Db> dbs_;
  std::map<std::string, uint32_t> byName_;
  mutable std::mutex mutex_;
};

// metadata.yaml's storage and files.
std::unique_ptr<Reader> openFolder(const std::string& dir) {
  const fs::path meta = fs::path(dir) / "metadata.yaml";
  if (!fs::is_regular_file(meta)) throw Error("'" + dir + "' is a folder without metadata.yaml: not a rosbag2 bag");
  std::string storage;
  std::vector<std::string> files;
  try {
    const YAML::Node info = YAML::LoadFile(meta.string())["rosbag2_bagfile_information"];
    if (!info) throw Error("no rosbag2_bagfile_information");
    storage = info["storage_identifier"].as<std::string>("");
    for (const auto& f : info["relative_file_paths"]) files.push_back((fs::path(dir) / f.as<std::string>()).string());
  } catch (const YAML::Exception& e) {
    throw Error("rosbag2 metadata '" + meta.string() + "': " + shown(e.what(), 120));
  } catch (const Error& e) {
    throw Error("rosbag2 metadata '" + meta.string() + "': " + e.what());
  }
  if (files.empty()) throw Error("rosbag2 metadata '" + meta.string() + "' lists no files");
  if (storage == "mcap") {
    if (files.size() > 1) throw Error("rosbag2 bag '" + dir + "' is split into several MCAP files: give one of them");
    return openMcap(files[0]);
  }
  if (storage != "sqlite3")
    throw Error("rosbag2 bag '" + dir + "' has storage '" + shown(storage) + "' (sqlite3 or mcap are read)");
  return std::make_unique<SqliteReader>(dir, files);
}

}  // namespace

std::unique_ptr<Reader> openRosbag2(const std::string& path) {
  if (fs::is_directory(path)) return openFolder(path);
  return std::make_unique<SqliteReader>(path, std::vector<std::string>{path});
}

std::unique_ptr<Reader> openReader(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return openRosbag2(path);
  if (!fs::exists(path, ec)) throw Error("log '" + path + "' does not exist");
  char head[16] = {};
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    const size_t got = std::fread(head, 1, sizeof head, f);
    std::fclose(f);
    const std::string h(head, got);
    if (h.rfind("\x89MCAP", 0) == 0) return openMcap(path);
    if (h.rfind("#ROSBAG V2.0", 0) == 0) return openRos1(path);
    if (h.rfind("#ROSBAG", 0) == 0) throw Error("'" + path + "' is a ROS 1 bag of an older format (2.0 is read)");
    if (h.rfind("SQLite format 3", 0) == 0) return openRosbag2(path);
  } else {
    throw Error("cannot open log '" + path + "': " + std::strerror(errno));
  }
  throw Error("'" + path + "' is not a log this reads (MCAP, ROS 1 bag 2.0, rosbag2 sqlite3 .db3 or bag folder)");
}

}  // namespace cs::logio
