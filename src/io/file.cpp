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

namespace {

Error write_error(const std::filesystem::path& path, const std::string& what) {
    Error e;
    e.code = ErrorCode::kCannotWrite;
    e.path = path.string();
    e.message = what;
    return e;
}

}  // namespace

Result<AtomicFileWriter> AtomicFileWriter::open(const std::filesystem::path& path) {
    const std::filesystem::path dir =
        path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
    // A unique temporary name beside the target so that rename() is atomic (same filesystem).
    std::random_device rd;
    char suffix[32];
    std::snprintf(suffix, sizeof suffix, ".tmp%08x%04x", rd(),
                  static_cast<unsigned>(::getpid()) & 0xffffu);
    std::string tmp_name = ".";
    tmp_name.append(path.filename().string()).append(suffix);
    AtomicFileWriter w;
    w.path_ = path;
    w.tmp_ = dir / tmp_name;
    w.fd_ = ::open(w.tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (w.fd_ < 0) {
        return write_error(path, std::string("cannot create a file in ") + dir.string() + ": " +
                                     std::strerror(errno));
    }
    return w;
}

AtomicFileWriter::AtomicFileWriter(AtomicFileWriter&& other) noexcept { *this = std::move(other); }

AtomicFileWriter& AtomicFileWriter::operator=(AtomicFileWriter&& other) noexcept {
    if (this == &other) return *this;
    abandon();
    path_ = std::move(other.path_);
    tmp_ = std::move(other.tmp_);
    fd_ = other.fd_;
    other.fd_ = -1;
    return *this;
}

AtomicFileWriter::~AtomicFileWriter() { abandon(); }

void AtomicFileWriter::abandon() {
    if (fd_ < 0) return;
    ::close(fd_);
    ::unlink(tmp_.c_str());
    fd_ = -1;
}

Status AtomicFileWriter::write(std::span<const std::byte> bytes) {
    if (fd_ < 0) return write_error(path_, "the file is closed");
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            abandon();
            return write_error(path_, std::string("cannot write: ") + std::strerror(err));
        }
        done += static_cast<std::size_t>(n);
    }
    return Ok{};
}

Status AtomicFileWriter::commit() {
    if (fd_ < 0) return write_error(path_, "the file is closed");
    if (::fsync(fd_) != 0 && errno != EINVAL) {
        const int err = errno;
        abandon();
        return write_error(path_, std::string("cannot flush: ") + std::strerror(err));
    }
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) {
        const int err = errno;
        ::unlink(tmp_.c_str());
        return write_error(path_, std::string("cannot close: ") + std::strerror(err));
    }
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmp_.c_str());
        return write_error(path_, std::string("cannot rename into place: ") + std::strerror(err));
    }
    return Ok{};
}

Status write_file_atomic(const std::filesystem::path& path, std::span<const std::byte> bytes) {
    auto w = AtomicFileWriter::open(path);
    if (!w) return w.error();
    if (auto s = w->write(bytes); !s) return s;
    return w->commit();
}

}  // namespace ncrev
