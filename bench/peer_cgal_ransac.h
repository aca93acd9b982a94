// The CGAL Efficient RANSAC types both RANSAC peers use (fitting, segmentation): points with
// normals as pairs, the exact-predicates kernel.
#pragma once

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>

#include <utility>
#include <vector>

namespace ncrev::bench::cgal_ransac {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Pwn = std::pair<K::Point_3, K::Vector_3>;
using Pwns = std::vector<Pwn>;
using Traits =
    CGAL::Shape_detection::Efficient_RANSAC_traits<K, Pwns, CGAL::First_of_pair_property_map<Pwn>,
                                                   CGAL::Second_of_pair_property_map<Pwn>>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;

}  // namespace ncrev::bench::cgal_ransac
