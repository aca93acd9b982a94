#include "ncrev/common.h"

namespace ncrev {

const char* to_string(ErrorCode code) {
    switch (code) {
        case ErrorCode::kCannotOpen:
            return "cannot-open";
        case ErrorCode::kCannotWrite:
            return "cannot-write";
        case ErrorCode::kEmpty:
            return "empty";
        case ErrorCode::kUnknownFormat:
            return "unknown-format";
        case ErrorCode::kTruncated:
            return "truncated";
        case ErrorCode::kSizeMismatch:
            return "size-mismatch";
        case ErrorCode::kBadNumber:
            return "bad-number";
        case ErrorCode::kBadSyntax:
            return "bad-syntax";
        case ErrorCode::kBadCount:
            return "bad-count";
        case ErrorCode::kBadValue:
            return "bad-value";
        case ErrorCode::kIndexOutOfRange:
            return "index-out-of-range";
        case ErrorCode::kDuplicateIndex:
            return "duplicate-index";
        case ErrorCode::kMissingIndex:
            return "missing-index";
        case ErrorCode::kTrailingContent:
            return "trailing-content";
        case ErrorCode::kTooLarge:
            return "too-large";
    }
    return "unknown";
}

std::string Error::describe() const {
    std::string s;
    if (!path.empty()) s += path + ": ";
    if (line >= 0) {
        s += "line " + std::to_string(line) + ": ";
    } else if (byte_offset >= 0) {
        s += "byte " + std::to_string(byte_offset) + ": ";
    }
    s += message;
    return s;
}

}  // namespace ncrev
