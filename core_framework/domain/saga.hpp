// A saga: the undo of each step that did something, registered by the step itself as soon as
// there is something to undo (also when the step then fails halfway), and run in reverse order.
// A launch rolls back so (launch.cpp): nothing it started, reserved or connected outlives it, and
// its failure says what was undone.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace rsca::domain {

class Saga {
public:
  // An undo returns what it undid, for the report ("3 processes terminated"); empty: nothing.
  using Undo = std::function<std::string()>;

  void on_undo(Undo undo) { undos_.push_back(std::move(undo)); }
  bool empty() const { return undos_.empty(); }

  // Runs every undo, the last registered first, once; what each undid, in that order.
  std::vector<std::string> roll_back() {
    std::vector<std::string> undone;
    while (!undos_.empty()) {
      auto undo = std::move(undos_.back());
      undos_.pop_back();
      if (auto what = undo(); !what.empty())
        undone.push_back(std::move(what));
    }
    return undone;
  }

  // The steps succeeded: their results are kept.
  void commit() { undos_.clear(); }

private:
  std::vector<Undo> undos_;
};

} // namespace rsca::domain
