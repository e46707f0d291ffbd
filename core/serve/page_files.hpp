// The files fba-run --serve may send: the built page's folder, read once when the server starts,
// each file by its exact name. No path is ever made from a request: a name either is in this list
// or is not found.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

namespace fba::serve {

struct PageFile {
  std::string content_type;
  std::string body;
};

class PageFiles {
 public:
  // The regular files under `dir` (hidden ones left out), by their path relative to it
  // ("index.html", "assets/index-3f2a.js"), read whole now. Without an index.html there: the
  // built-in page, which says how to build the front end and still shows the live stream.
  static PageFiles load(const std::filesystem::path& dir);

  // The file of that exact name; null when there is none.
  const PageFile* find(std::string_view name) const;
  // The front end's build was found (else the built-in page stands in for it).
  bool built() const { return built_; }
  std::size_t size() const { return files_.size(); }

 private:
  std::map<std::string, PageFile, std::less<>> files_;
  bool built_ = false;
};

// share/fba beside the program's bin folder (the build tree and an installation alike): the page
// in web/.
std::filesystem::path share_dir();
// Where the built page is: FBA_WEB_DIR when set, else share_dir()/web.
std::filesystem::path find_web_dir();

// What a file's name says it holds, for Content-Type.
std::string content_type_of(std::string_view name);

// The page served when the front end is not built.
extern const char* const kBuiltInPage;

}  // namespace fba::serve
