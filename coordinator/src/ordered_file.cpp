#include "sphfsi/coordinator/ordered_file.hpp"

// Why a driver of our own. HDF5 writes a flush in the order of its metadata cache, the superblock last,
// and that order is not safe to stop: killed in between, a file's chunk index pointed at a chunk beyond the
// end of the allocated space the superblock still announced ("addr overflow" in every reader), a new
// index node's parent was on disk before the node ("wrong B-tree signature"), a group listed a dataset
// whose header was not there yet. HDF5 only guarantees order to SWMR readers, and SWMR's superblock
// marks a killed writer's file "open for write" to every plain reader.
//
// This driver (after HDF5's default "sec2" one: plain pread/pwrite on one file) writes raw data into newly
// allocated space at once, as sec2 does, but holds everything else until the flush ends, then writes it in
// an order in which every prefix is a readable file:
//   1. the superblock: its end of allocation now covers all that follows (the file is lengthened first, as
//      a superblock announcing more than the file holds reads as truncated);
//   2. whatever lies in space allocated since the last flush, which nothing on disk refers to yet, and raw
//      data rewritten in older space: rows beyond a dataset's extent, and global heap collections (string
//      attribute values, which HDF5 hands to drivers as raw data);
//   3. rewritten metadata in older space, things referred to before what refers to them: local heaps (link
//      names), then B-tree nodes from the root down (a parent names a new child only once the child is
//      written; a node that gave half its entries to a new sibling shrinks only after its parent names
//      that sibling), group symbol-table nodes after the B-trees that lead to them, then object headers (a
//      dataset's row count last, so that its new row is indexed before it is counted).
// It never hands out again space that the file on disk may still refer to: the file is created with no
// free-space manager (create_file), and the end of allocation never drops below what the disk announces.
// A local heap (a group's link names) that has moved is two pieces, rewritten one after the other: groups
// are created with room for their names (create_groups) so that theirs never move once on disk.
// The metadata accumulator and the space aggregators are not offered (query below): the one would merge
// writes of all stages into one, the other would hand back unused space at a flush for reuse.
// integration.record_kill kills a recording before each one of its writes and reads the file each time.
//
// The order protects against a killed process ("a run stopped at any moment", docs/record.md), not against a crash of the operating system or a power cut: that would take an fdatasync between the
// stages, a cost at every frame that we have not taken.
//
// A write that fails (a full disk) leaves the file as it is and stops all later ones: HDF5 takes a write
// the driver accepted as done, so writing on after a gap could mix two states. The file's new length is
// reserved (fallocate) before anything is written, so a full disk is found before the first write of a
// flush (reserve). The failing flush reports it; later ones fail too, except the one closing the file, which
// succeeds writing nothing, since HDF5 1.10 frees a file whose closing flush failed yet keeps its
// identifier (a crash when the library shuts down).

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sphfsi::coordinator::h5 {
namespace {

struct PendingWrite {
    H5FD_mem_t type;
    haddr_t addr;
    std::vector<unsigned char> bytes;
};

struct OrderedFile {
    H5FD_t pub;  // first member: HDF5 holds an OrderedFile* as its H5FD_t*
    int fd = -1;
    dev_t device = 0;
    ino_t inode = 0;
    haddr_t eoa = 0;        // end of the space HDF5 has allocated
    haddr_t eof = 0;        // the file's length on disk
    haddr_t published = 0;  // the end of allocation in the superblock on disk
    bool shrink_wanted = false;
    bool failed = false;  // a write failed: nothing more is written
    std::vector<PendingWrite> pending;  // held since the last flush, in HDF5's order
};
static_assert(std::is_standard_layout_v<OrderedFile>, "HDF5 holds a pointer to the first member");

OrderedFile& of(H5FD_t* f) { return *reinterpret_cast<OrderedFile*>(f); }
const OrderedFile& of(const H5FD_t* f) { return *reinterpret_cast<const OrderedFile*>(f); }

std::string first_failure;  // of this process, for the error message

bool fail(OrderedFile& f, const char* what) {
    if (first_failure.empty()) first_failure = std::string(what) + ": " + std::strerror(errno);
    f.failed = true;
    return false;
}

bool write_all(OrderedFile& f, haddr_t at, const unsigned char* p, std::size_t n) {
    while (n > 0) {
        const ssize_t k = pwrite(f.fd, p, n, static_cast<off_t>(at));
        if (k < 0 && errno == EINTR) continue;
        if (k == 0) errno = EIO;  // no progress and no reason given
        if (k <= 0) return fail(f, "cannot write");
        p += k;
        n -= static_cast<std::size_t>(k);
        at += static_cast<haddr_t>(k);
    }
    f.eof = std::max(f.eof, at);
    return true;
}

// Allocates the blocks of [published, eoa), the space a flush may write below its end, growing the file to
// `eoa`: no write of the flush can then find the disk full. (Where the file system cannot allocate ahead,
// the file is only lengthened, and a full disk shows at a write, still after a readable prefix.)
bool reserve(OrderedFile& f) {
    if (f.eoa <= f.published) return true;
    if (fallocate(f.fd, 0, static_cast<off_t>(f.published), static_cast<off_t>(f.eoa - f.published)) == 0) {
        f.eof = std::max(f.eof, f.eoa);
        return true;
    }
    if (errno != EOPNOTSUPP && errno != ENOSYS) return fail(f, "cannot grow the file");
    if (f.eof < f.eoa && ftruncate(f.fd, static_cast<off_t>(f.eoa)) != 0) return fail(f, "cannot grow the file");
    f.eof = std::max(f.eof, f.eoa);
    return true;
}

bool is_superblock(const PendingWrite& w) { return w.type == H5FD_MEM_SUPER && w.addr == 0; }

// The place of a held write in the order of the header comment, earliest first.
std::tuple<int, int> stage(const PendingWrite& w, haddr_t published) {
    if (is_superblock(w)) return {0, 0};
    if (w.addr >= published || w.type == H5FD_MEM_DRAW) return {1, 0};
    if (w.type == H5FD_MEM_LHEAP) return {2, 0};
    if (w.type == H5FD_MEM_BTREE) {
        // A version-1 B-tree node starts "TREE", node type, level (HDF5 File Format Specification, III.A.1);
        // anything else of this type is a symbol-table node ("SNOD"), a leaf of a group's B-tree.
        const bool tree = w.bytes.size() > 5 && std::memcmp(w.bytes.data(), "TREE", 4) == 0;
        return {3, tree ? -static_cast<int>(w.bytes[5]) : 1};
    }
    return {4, 0};
}

bool release(OrderedFile& f, bool closing = false) {
    if (f.failed) return false;
    // A flush of some objects only (H5Dflush, which we do not call) leaves the superblock out: holding on
    // until it comes keeps its end of allocation ahead of what it covers.
    if (!closing && f.eoa != f.published && std::none_of(f.pending.begin(), f.pending.end(), is_superblock)) return true;
    if (!reserve(f)) return false;
    const haddr_t on_disk = f.published;
    std::stable_sort(f.pending.begin(), f.pending.end(), [&](const PendingWrite& a, const PendingWrite& b) {
        return stage(a, on_disk) < stage(b, on_disk);
    });
    for (const PendingWrite& w : f.pending) {
        if (!write_all(f, w.addr, w.bytes.data(), w.bytes.size())) return false;
        if (is_superblock(w)) f.published = f.eoa;
    }
    f.pending.clear();
    if (f.shrink_wanted && f.eof > f.eoa && f.published == f.eoa) {
        if (ftruncate(f.fd, static_cast<off_t>(f.eoa)) != 0) return fail(f, "cannot shorten the file");
        f.eof = f.eoa;
    }
    f.shrink_wanted = false;
    return true;
}

H5FD_t* open_file(const char* name, unsigned flags, hid_t, haddr_t) {
    int mode = (flags & H5F_ACC_RDWR) ? O_RDWR : O_RDONLY;
    if (flags & H5F_ACC_TRUNC) mode |= O_TRUNC;
    if (flags & H5F_ACC_CREAT) mode |= O_CREAT;
    if (flags & H5F_ACC_EXCL) mode |= O_EXCL;
    const int fd = ::open(name, mode | O_CLOEXEC, 0666);  // not inherited by the participants we start
    struct stat st;
    if (fd < 0) return nullptr;  // not a failure to report: HDF5 probes for files that need not exist
    if (fstat(fd, &st) != 0) {
        ::close(fd);
        return nullptr;
    }
    auto* f = new (std::nothrow) OrderedFile{};
    if (!f) {
        ::close(fd);
        return nullptr;
    }
    f->fd = fd;
    f->device = st.st_dev;
    f->inode = st.st_ino;
    f->eof = f->published = static_cast<haddr_t>(st.st_size);
    return &f->pub;
}

herr_t close_file(H5FD_t* file) {
    OrderedFile* f = &of(file);
    release(*f, true);  // a failure is kept for the message (see the header comment for why not returned)
    ::close(f->fd);
    delete f;
    return 0;
}

int compare(const H5FD_t* a, const H5FD_t* b) {
    const auto key = [](const OrderedFile& f) { return std::make_pair(f.device, f.inode); };
    return key(of(a)) < key(of(b)) ? -1 : key(of(b)) < key(of(a)) ? 1 : 0;
}

herr_t query(const H5FD_t*, unsigned long* flags) {
    *flags = H5FD_FEAT_DATA_SIEVE | H5FD_FEAT_POSIX_COMPAT_HANDLE | H5FD_FEAT_DEFAULT_VFD_COMPATIBLE;
    return 0;
}

haddr_t get_eoa(const H5FD_t* file, H5FD_mem_t) { return of(file).eoa; }

herr_t set_eoa(H5FD_t* file, H5FD_mem_t, haddr_t addr) {
    // HDF5 lowers the end of allocation when it frees a block at the end; below what the disk announces,
    // that block may still be referred to there, and allocating it again would overwrite it.
    OrderedFile& f = of(file);
    f.eoa = std::max(addr, f.published);
    return 0;
}

haddr_t get_eof(const H5FD_t* file, H5FD_mem_t) {
    const OrderedFile& f = of(file);
    haddr_t end = f.eof;
    for (const PendingWrite& w : f.pending) end = std::max(end, w.addr + w.bytes.size());
    return end;
}

herr_t get_handle(H5FD_t* file, hid_t, void** handle) {
    *handle = &of(file).fd;
    return 0;
}

herr_t read(H5FD_t* file, H5FD_mem_t, hid_t, haddr_t addr, size_t size, void* buffer) {
    const OrderedFile& f = of(file);
    auto* out = static_cast<unsigned char*>(buffer);
    for (std::size_t done = 0; done < size;) {
        const ssize_t k = pread(f.fd, out + done, size - done, static_cast<off_t>(addr + done));
        if (k < 0 && errno == EINTR) continue;
        if (k < 0) return -1;
        if (k == 0) {  // past the end of the file: zeros, as in sec2
            std::memset(out + done, 0, size - done);
            break;
        }
        done += static_cast<std::size_t>(k);
    }
    for (const PendingWrite& w : f.pending) {  // what is held, newest last, over what is on disk
        const haddr_t from = std::max(addr, w.addr), to = std::min(addr + size, w.addr + w.bytes.size());
        if (from < to) std::memcpy(out + (from - addr), w.bytes.data() + (from - w.addr), to - from);
    }
    return 0;
}

herr_t write(H5FD_t* file, H5FD_mem_t type, hid_t, haddr_t addr, size_t size, const void* buffer) {
    OrderedFile& f = of(file);
    const auto* p = static_cast<const unsigned char*>(buffer);
    if (f.failed) return 0;  // dropped: the file keeps the state of its last whole flush
    // Raw data in new space: nothing refers to it until the flush.
    if (type == H5FD_MEM_DRAW && addr >= f.published) return write_all(f, addr, p, size) ? 0 : -1;
    try {
        // The same entry again replaces the one held, and goes last, as it was written last.
        std::erase_if(f.pending, [&](const PendingWrite& w) { return w.addr == addr && w.type == type && w.bytes.size() == size; });
        f.pending.push_back({type, addr, std::vector<unsigned char>(p, p + size)});
    } catch (const std::bad_alloc&) {
        errno = ENOMEM;
        return fail(f, "cannot hold a write") ? 0 : -1;
    }
    return 0;
}

herr_t flush(H5FD_t* file, hid_t, hbool_t closing) { return release(of(file)) || closing ? 0 : -1; }

herr_t truncate(H5FD_t* file, hid_t, hbool_t closing) {
    OrderedFile& f = of(file);
    if (f.failed) return closing ? 0 : -1;
    if (f.eof < f.eoa) return reserve(f) || closing ? 0 : -1;
    f.shrink_wanted = f.eof > f.eoa;  // once the superblock that says so is on disk: at the flush that follows
    return 0;
}

herr_t lock(H5FD_t* file, hbool_t rw) {
    if (flock(of(file).fd, (rw ? LOCK_EX : LOCK_SH) | LOCK_NB) == 0 || errno == ENOSYS) return 0;
    return -1;
}

herr_t unlock(H5FD_t* file) {
    if (flock(of(file).fd, LOCK_UN) == 0 || errno == ENOSYS) return 0;
    return -1;
}

const H5FD_class_t kOrderedFile = {
    .name = "sphfsi_ordered",
    .maxaddr = (static_cast<haddr_t>(1) << (8 * sizeof(off_t) - 1)) - 1,
    .fc_degree = H5F_CLOSE_WEAK,
    .terminate = nullptr,
    .sb_size = nullptr,
    .sb_encode = nullptr,
    .sb_decode = nullptr,
    .fapl_size = 0,
    .fapl_get = nullptr,
    .fapl_copy = nullptr,
    .fapl_free = nullptr,
    .dxpl_size = 0,
    .dxpl_copy = nullptr,
    .dxpl_free = nullptr,
    .open = open_file,
    .close = close_file,
    .cmp = compare,
    .query = query,
    .get_type_map = nullptr,
    .alloc = nullptr,
    .free = nullptr,
    .get_eoa = get_eoa,
    .set_eoa = set_eoa,
    .get_eof = get_eof,
    .get_handle = get_handle,
    .read = read,
    .write = write,
    .flush = flush,
    .truncate = truncate,
    .lock = lock,
    .unlock = unlock,
    .fl_map = H5FD_FLMAP_DICHOTOMY,
};
}  // namespace

const std::string& ordered_file_failure() { return first_failure; }

void use_ordered_file_driver(hid_t fapl) {
    static const hid_t driver = H5FDregister(&kOrderedFile);
    if (driver < 0 || H5Pset_driver(fapl, driver, nullptr) < 0)
        throw std::runtime_error("HDF5: cannot use the record's file driver");
}

}  // namespace sphfsi::coordinator::h5
