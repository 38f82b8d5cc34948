#include "cullide/pipeline.h"

#include <chrono>

namespace cullide {

const char* to_string(Method m) {
    switch (m) {
        case Method::Exact:
            return "exact";
    }
    return "?";
}

std::vector<std::string> method_names() { return {"exact"}; }

Result<Method> parse_method(std::string_view name) {
    if (name == "exact") return Method::Exact;
    std::string valid;
    for (const std::string& n : method_names()) valid += (valid.empty() ? "" : ", ") + n;
    return Error{"unknown method '" + std::string(name) + "' (valid: " + valid + ")"};
}

Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options) {
    if (options.threads < 0) return Error{"threads must be >= 0 (got " + std::to_string(options.threads) + ")"};
    const auto start = std::chrono::steady_clock::now();
    FrameResult result;
    switch (options.method) {
        case Method::Exact: {
            ExactStats es;
            Result<std::vector<TrianglePair>> pairs =
                exact_pairs(objects, ExactOptions{options.self, options.threads}, &es);
            if (!pairs) return pairs.error();
            result.pairs = std::move(pairs).value();
            result.stats.candidate_triangles = es.candidate_triangles;
            result.stats.exact_tests = es.box_pairs;
            result.stats.adjacent_skipped = es.adjacent_skipped;
            result.stats.triangles = es.triangles;
            break;
        }
    }
    result.object_pairs = object_pairs(result.pairs);
    result.stats.objects = objects.size();
    result.stats.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace cullide
