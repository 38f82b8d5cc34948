// cullide/result.h: the error type of the cullide library.
//
// Every operation that can fail on caller data (a file, a mesh, an option) returns Result<T> or
// Status. The message names what is wrong and where ("file.obj:12: face index 9 is beyond the
// vertex list (size 8)"). A failed call changes nothing the caller can see.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace cullide {

struct Error {
    std::string message;
};

// Either a value or an Error. Cheap to move; value() on an error is a bug (asserts).
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

}  // namespace cullide
