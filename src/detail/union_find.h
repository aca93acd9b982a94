// Union-find over 0..n-1 whose root is always the smallest index of its set: what it joins
// does not depend on the order of the unions (deterministic numbering by first member).
#pragma once

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace ncrev::detail {

struct MinUnionFind {
    std::vector<std::uint32_t> parent;
    explicit MinUnionFind(std::size_t n) : parent(n) {
        std::iota(parent.begin(), parent.end(), 0u);
    }
    /// A new member in a set of its own; its index.
    std::uint32_t add() {
        parent.push_back(static_cast<std::uint32_t>(parent.size()));
        return parent.back();
    }
    std::uint32_t find(std::uint32_t a) {
        while (parent[a] != a) {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        return a;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b) std::swap(a, b);
        parent[a] = b;
    }
};

}  // namespace ncrev::detail
