// File access for io: read-only memory mapping of inputs, atomic writing of outputs.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <random>

#include "ncrev/io.h"

namespace ncrev {

namespace {

Error open_error(const std::filesystem::path& path, const std::string& what) {
    Error e;
    e.code = ErrorCode::kCannotOpen;
    e.path = path.string();
    e.message = what;
    return e;
}

}  // namespace

Result<FileBytes> FileBytes::open(const std::filesystem::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return open_error(path, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        ::close(fd);
        return open_error(path, std::string("cannot stat: ") + std::strerror(err));
    }
    if (S_ISDIR(st.st_mode)) {
        ::close(fd);
        return open_error(path, "is a directory, expected a mesh file");
    }
    FileBytes out;
    if (S_ISREG(st.st_mode) && st.st_size > 0) {
        void* p =
            ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
        if (p != MAP_FAILED) {
            ::madvise(p, static_cast<std::size_t>(st.st_size), MADV_SEQUENTIAL);
            out.data_ = static_cast<const std::byte*>(p);
            out.size_ = static_cast<std::size_t>(st.st_size);
            out.mapped_ = true;
            ::close(fd);
            return out;
        }
    }
    // Not mappable (a pipe, /dev/stdin, an empty file): read it.
    std::byte buf[1 << 16];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            return open_error(path, std::string("cannot read: ") + std::strerror(err));
        }
        if (n == 0) break;
        out.owned_.insert(out.owned_.end(), buf, buf + n);
    }
    ::close(fd);
    out.data_ = out.owned_.data();
    out.size_ = out.owned_.size();
    return out;
}

FileBytes::FileBytes(FileBytes&& other) noexcept { *this = std::move(other); }

FileBytes& FileBytes::operator=(FileBytes&& other) noexcept {
    if (this == &other) return *this;
    if (mapped_) ::munmap(const_cast<std::byte*>(data_), size_);
    mapped_ = other.mapped_;
    owned_ = std::move(other.owned_);
    size_ = other.size_;
    data_ = mapped_ ? other.data_ : owned_.data();
    other.data_ = nullptr;
    other.size_ = 0;
    other.mapped_ = false;
    return *this;
}

FileBytes::~FileBytes() {
    if (mapped_) ::munmap(const_cast<std::byte*>(data_), size_);
}

Status write_file_atomic(const std::filesystem::path& path, std::span<const std::byte> bytes) {
    auto fail = [&](const std::string& what) -> Status {
        Error e;
        e.code = ErrorCode::kCannotWrite;
        e.path = path.string();
        e.message = what;
        return e;
    };
    const std::filesystem::path dir =
        path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
    // A unique temporary name beside the target so that rename() is atomic (same filesystem).
    std::random_device rd;
    char suffix[32];
    std::snprintf(suffix, sizeof suffix, ".tmp%08x%04x", rd(),
                  static_cast<unsigned>(::getpid()) & 0xffffu);
    std::string tmp_name = ".";
    tmp_name.append(path.filename().string()).append(suffix);
    const std::filesystem::path tmp = dir / tmp_name;
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        return fail(std::string("cannot create a file in ") + dir.string() + ": " +
                    std::strerror(errno));
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            ::unlink(tmp.c_str());
            return fail(std::string("cannot write: ") + std::strerror(err));
        }
        done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd) != 0 && errno != EINVAL) {
        const int err = errno;
        ::close(fd);
        ::unlink(tmp.c_str());
        return fail(std::string("cannot flush: ") + std::strerror(err));
    }
    if (::close(fd) != 0) {
        ::unlink(tmp.c_str());
        return fail(std::string("cannot close: ") + std::strerror(errno));
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        return fail(std::string("cannot rename into place: ") + std::strerror(err));
    }
    return Ok{};
}

}  // namespace ncrev
