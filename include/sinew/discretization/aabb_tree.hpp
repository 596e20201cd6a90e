// A bounding-volume hierarchy of axis-aligned boxes (median splits along the longest axis, up to four
// items per leaf) with the three queries contact needs: the items whose box contains a point (which
// element holds a surface sample), the items within a distance of a point (surface triangles near a
// sample), and branch-and-bound nearest item (the closest surface point, the distance to a collider).
// A fourth, descend, lets a caller treat a whole subtree in bulk (the far field of a fast winding number).
// Host only; built in O(n log n), rebuilt when positions change, or refitted in O(n) (the same split of
// the items, each node's box recomputed) when they change a little.
#pragma once

#include <sinew/discretization/geometry.hpp>

#include <algorithm>
#include <numeric>
#include <vector>

namespace sinew::geom {

class AabbTree {
 public:
  AabbTree() = default;
  explicit AabbTree(const std::vector<Box>& boxes) { build(boxes); }

  void build(const std::vector<Box>& boxes) {
    boxes_ = boxes;
    nodes_.clear();
    items_.resize(boxes.size());
    std::iota(items_.begin(), items_.end(), 0);
    if (boxes.empty()) return;
    nodes_.reserve(2 * boxes.size() / kLeaf + 2);
    split(0, static_cast<int>(boxes.size()), boxes);
  }
  bool empty() const { return nodes_.empty(); }
  std::size_t items() const { return boxes_.size(); }

  // New boxes for the same items (boxes.size() == items()): the nodes keep their items and take the
  // union of the new boxes. Every query stays exact; only its speed depends on how far the items moved
  // since the last build (the split no longer follows them).
  void refit(const std::vector<Box>& boxes) {
    boxes_ = boxes;
    // Parents come before their children (split is preorder): children are refitted first.
    for (int i = static_cast<int>(nodes_.size()) - 1; i >= 0; --i) {
      Node& n = nodes_[i];
      Box box;
      if (n.left < 0) {
        for (int k = n.begin; k < n.end; ++k) box.add(boxes_[items_[k]]);
      } else {
        box.add(nodes_[n.left].box);
        box.add(nodes_[n.right].box);
      }
      n.box = box;
    }
  }

  // The nodes, parents before children; node i holds the items item(begin)..item(end - 1) of its range.
  int node_count() const { return static_cast<int>(nodes_.size()); }
  const Box& node_box(int i) const { return nodes_[i].box; }
  int node_begin(int i) const { return nodes_[i].begin; }
  int node_end(int i) const { return nodes_[i].end; }
  int item(int k) const { return items_[k]; }

  // From the root down: bulk(node) returns true when it has accounted for the node's items as a whole
  // (its subtree is skipped); otherwise the children are visited, and at a leaf fn(item) for each item.
  template <class Bulk, class Fn>
  void descend(Bulk&& bulk, Fn&& fn) const {
    if (nodes_.empty()) return;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const int id = stack[--top];
      const Node& n = nodes_[id];
      if (bulk(id)) continue;
      if (n.left < 0) {
        for (int k = n.begin; k < n.end; ++k) fn(items_[k]);
      } else if (top + 2 <= 128) {  // always, with median splits (depth ~ log2 n)
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
  }

  // fn(item) for every item whose box contains p.
  template <class Fn>
  void at_point(const Vec& p, Fn&& fn) const {
    visit([&](const Box& b) { return b.contains(p); }, fn);
  }
  // fn(item) for every item whose box lies within distance r of p.
  template <class Fn>
  void near(const Vec& p, double r, Fn&& fn) const {
    const double r2 = r * r;
    visit([&](const Box& b) { return b.distance2(p) <= r2; }, fn);
  }
  // The item with the smallest d2(item) (the squared distance from p to it; +inf to skip an item)
  // among those closer than sqrt(limit2); -1 when none is. best2 receives its squared distance.
  template <class D2>
  int closest(const Vec& p, double limit2, D2&& d2, double& best2) const {
    best2 = limit2;
    int best = -1;
    if (nodes_.empty()) return best;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (n.box.distance2(p) >= best2) continue;
      if (n.left < 0) {
        for (int k = n.begin; k < n.end; ++k) {
          if (boxes_[items_[k]].distance2(p) >= best2) continue;
          const double d = d2(items_[k]);
          if (d < best2) {
            best2 = d;
            best = items_[k];
          }
        }
        continue;
      }
      // Nearer child last, so that it is searched first and tightens the bound.
      const double dl = nodes_[n.left].box.distance2(p), dr = nodes_[n.right].box.distance2(p);
      if (top + 2 > 128) continue;  // unreachable with median splits (depth ~ log2 n)
      if (dl < dr) {
        stack[top++] = n.right;
        stack[top++] = n.left;
      } else {
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
    return best;
  }

 private:
  static constexpr int kLeaf = 4;
  struct Node {
    Box box;
    int left = -1, right = -1;  // children; -1 for a leaf
    int begin = 0, end = 0;     // the node's items_[begin, end)
  };

  int split(int begin, int end, const std::vector<Box>& boxes) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Box box, centers;
    for (int k = begin; k < end; ++k) {
      box.add(boxes[items_[k]]);
      centers.add(boxes[items_[k]].center());
    }
    nodes_[id].box = box;
    nodes_[id].begin = begin;
    nodes_[id].end = end;
    if (end - begin <= kLeaf) return id;
    int axis = 0;
    for (int i = 1; i < 3; ++i)
      if (centers.hi[i] - centers.lo[i] > centers.hi[axis] - centers.lo[axis]) axis = i;
    const int mid = (begin + end) / 2;
    std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                     [&](int a, int b) { return boxes[a].center()[axis] < boxes[b].center()[axis]; });
    const int l = split(begin, mid, boxes);
    const int r = split(mid, end, boxes);
    nodes_[id].left = l;
    nodes_[id].right = r;
    return id;
  }

  // fn(item) for the items whose box satisfies pred, skipping subtrees whose box does not.
  template <class Pred, class Fn>
  void visit(Pred&& pred, Fn&& fn) const {
    descend([&](int node) { return !pred(nodes_[node].box); },
            [&](int item) {
              if (pred(boxes_[item])) fn(item);
            });
  }

  std::vector<Box> boxes_;
  std::vector<Node> nodes_;
  std::vector<int> items_;
};

}  // namespace sinew::geom
