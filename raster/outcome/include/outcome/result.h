// outcome/result.h: the error type of every cullide library (Error, Result<T>, Status).
//
// One header-only target, cullide::outcome (defined in raster/CMakeLists.txt, links nothing), that
// raster and spatialhash both link, so neither copies it and spatialhash still does not depend on
// raster; each module names the types in its own namespace (raster/result.h,
// spatialhash/result.h, cullide/result.h), so raster::Error, spatialhash::Error and cullide::Error
// are one type.
//
// Every call that can fail on caller data returns Result<T> or Status; the message names the
// element, its index and the limit ("draw 3: index 17 at position 5 is beyond the vertex list
// (size 12)"). A failed call changes nothing the caller can see.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace outcome {

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

// Success, or an Error.
class [[nodiscard]] Status {
   public:
    Status() = default;
    Status(Error error) : error_(std::move(error)), failed_(true) {}  // NOLINT(google-explicit-constructor)

    [[nodiscard]] bool ok() const { return !failed_; }
    explicit operator bool() const { return ok(); }
    [[nodiscard]] const Error& error() const {
        assert(failed_);
        return error_;
    }

   private:
    Error error_;
    bool failed_ = false;
};

}  // namespace outcome
