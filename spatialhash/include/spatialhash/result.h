// spatialhash/result.h: the error type of the spatialhash library.
//
// spatialhash sits below cullide in the module graph, so it carries its own small error type
// instead of cullide::Result. Every entry point that can fail on caller data returns Result<T>;
// the message names the element and the limit ("box 17: lo[1] = nan is not finite"). A failed
// call has no effect the caller can see.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace spatialhash {

struct Error {
    std::string message;
};

// Either a value or an Error. value() on an error is a bug (asserts).
template <class T>
class [[nodiscard]] Result {
   public:
    Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
    Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

    [[nodiscard]] bool ok() const { return v_.index() == 0; }
    explicit operator bool() const { return ok(); }

    [[nodiscard]] T& value() & {
        assert(ok());
        return std::get<0>(v_);
    }
    [[nodiscard]] const T& value() const& {
        assert(ok());
        return std::get<0>(v_);
    }
    [[nodiscard]] T&& value() && {
        assert(ok());
        return std::get<0>(std::move(v_));
    }
    [[nodiscard]] const Error& error() const {
        assert(!ok());
        return std::get<1>(v_);
    }

   private:
    std::variant<T, Error> v_;
};

}  // namespace spatialhash
