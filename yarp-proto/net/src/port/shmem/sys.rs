//! The operating-system objects of a C++-compatible shmem ring: a System V shared-memory
//! segment, and a process-shared pthread mutex alone in a mapped file (what ACE's
//! `ACE_Mutex(USYNC_PROCESS, name)` makes on Linux, where ACE opens `name` as a plain
//! file). Everything unsafe of the carrier is here.

use std::ffi::CString;
use std::io;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Permissions of what we create (ACE's `ACE_DEFAULT_FILE_PERMS`).
const PERMS: libc::c_int = 0o644;

/// A System V shared-memory segment attached to this process.
pub(crate) struct Segment {
    id: libc::c_int,
    ptr: *mut u8,
    len: usize,
    /// Marked for removal: it disappears once the last process detaches.
    removed: bool,
}

// SAFETY: the segment is plain memory; every access goes through raw pointers by the one
// thread that owns the connection.
unsafe impl Send for Segment {}

impl Segment {
    /// Creates a fresh segment of `len` bytes under `key`. A segment left under that key
    /// by a process that is gone (nobody attached) is removed first; one in use is an error.
    pub(crate) fn create(key: i32, len: usize) -> io::Result<Segment> {
        for _ in 0..2 {
            // SAFETY: plain system call.
            let id = unsafe { libc::shmget(key, len, libc::IPC_CREAT | libc::IPC_EXCL | PERMS) };
            if id >= 0 {
                return Segment::attach_id(id);
            }
            let err = io::Error::last_os_error();
            if err.raw_os_error() != Some(libc::EEXIST) {
                return Err(err);
            }
            // SAFETY: plain system call.
            let stale = unsafe { libc::shmget(key, 0, 0) };
            if stale < 0 || stat(stale)?.shm_nattch > 0 {
                return Err(io::Error::new(
                    io::ErrorKind::AddrInUse,
                    format!("shared-memory key {key} is in use by another connection"),
                ));
            }
            remove_id(stale);
        }
        Err(io::Error::new(
            io::ErrorKind::AddrInUse,
            format!("shared-memory key {key} stays taken"),
        ))
    }

    /// Attaches the existing segment `key`.
    pub(crate) fn open(key: i32) -> io::Result<Segment> {
        // SAFETY: plain system call.
        let id = unsafe { libc::shmget(key, 0, 0) };
        if id < 0 {
            let e = io::Error::last_os_error();
            return Err(io::Error::new(
                e.kind(),
                format!("no shared-memory segment with key {key}: {e}"),
            ));
        }
        Segment::attach_id(id)
    }

    fn attach_id(id: libc::c_int) -> io::Result<Segment> {
        let len = stat(id)?.shm_segsz;
        // SAFETY: attaching a segment the kernel sized; the mapping is `len` bytes long.
        let ptr = unsafe { libc::shmat(id, std::ptr::null(), 0) };
        if ptr as isize == -1 {
            return Err(io::Error::last_os_error());
        }
        Ok(Segment {
            id,
            ptr: ptr.cast(),
            len,
            removed: false,
        })
    }

    /// Bytes of the segment.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The start of the mapping (valid for `len` bytes while `self` lives).
    pub(crate) fn ptr(&self) -> *mut u8 {
        self.ptr
    }

    /// How many processes have it attached.
    pub(crate) fn attached(&self) -> usize {
        stat(self.id).map_or(0, |s| s.shm_nattch as usize)
    }

    /// Marks the segment for removal: nobody can attach it by key any more, and the
    /// kernel frees it when the last process detaches (also if this one dies).
    pub(crate) fn remove(&mut self) {
        if !self.removed {
            self.removed = true;
            remove_id(self.id);
        }
    }
}

impl Drop for Segment {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from `shmat` and is detached once.
        unsafe {
            libc::shmdt(self.ptr.cast());
        }
    }
}

fn stat(id: libc::c_int) -> io::Result<libc::shmid_ds> {
    // SAFETY: `shmid_ds` is plain data that `shmctl` fills.
    unsafe {
        let mut ds: libc::shmid_ds = std::mem::zeroed();
        if libc::shmctl(id, libc::IPC_STAT, &mut ds) < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(ds)
    }
}

fn remove_id(id: libc::c_int) {
    // SAFETY: plain system call.
    unsafe {
        libc::shmctl(id, libc::IPC_RMID, std::ptr::null_mut());
    }
}

/// A process-shared pthread mutex in a file, as ACE keeps one.
pub(crate) struct ProcessMutex {
    ptr: *mut libc::pthread_mutex_t,
    /// Set when this side created the file: it removes it when done.
    owned: Option<PathBuf>,
}

// SAFETY: a process-shared mutex may be used from any thread, also at once.
unsafe impl Send for ProcessMutex {}
// SAFETY: as above: pthread_mutex_lock/unlock are the only access, and they synchronise.
unsafe impl Sync for ProcessMutex {}

const MUTEX_LEN: usize = std::mem::size_of::<libc::pthread_mutex_t>();

impl ProcessMutex {
    /// Creates the mutex file (replacing a stale one: the peer opens it only after this
    /// side said it exists) and initialises the mutex, unlocked.
    pub(crate) fn create(path: &Path) -> io::Result<ProcessMutex> {
        let _ = std::fs::remove_file(path);
        let fd = open(path, libc::O_RDWR | libc::O_CREAT | libc::O_EXCL)?;
        // SAFETY: `fd` is ours; the mapping covers exactly the mutex.
        let m = unsafe {
            if libc::ftruncate(fd, MUTEX_LEN as libc::off_t) < 0 {
                let e = io::Error::last_os_error();
                libc::close(fd);
                let _ = std::fs::remove_file(path);
                return Err(e);
            }
            let ptr = map(fd);
            if ptr.is_null() {
                let _ = std::fs::remove_file(path);
                return Err(io::Error::last_os_error());
            }
            let mut attr: libc::pthread_mutexattr_t = std::mem::zeroed();
            libc::pthread_mutexattr_init(&mut attr);
            libc::pthread_mutexattr_setpshared(&mut attr, libc::PTHREAD_PROCESS_SHARED);
            let rc = libc::pthread_mutex_init(ptr, &attr);
            libc::pthread_mutexattr_destroy(&mut attr);
            let m = ProcessMutex {
                ptr,
                owned: Some(path.to_path_buf()),
            };
            if rc != 0 {
                return Err(io::Error::from_raw_os_error(rc));
            }
            m
        };
        Ok(m)
    }

    /// Opens the mutex the peer created.
    pub(crate) fn open(path: &Path) -> io::Result<ProcessMutex> {
        let fd = open(path, libc::O_RDWR)?;
        // SAFETY: `fd` is ours; the file is checked to hold a whole mutex before mapping.
        unsafe {
            let mut st: libc::stat = std::mem::zeroed();
            if libc::fstat(fd, &mut st) < 0 || (st.st_size as usize) < MUTEX_LEN {
                libc::close(fd);
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("{} is not a mutex file", path.display()),
                ));
            }
            let ptr = map(fd);
            if ptr.is_null() {
                return Err(io::Error::last_os_error());
            }
            Ok(ProcessMutex { ptr, owned: None })
        }
    }

    /// Locks, waiting at most `wait`; false on time-out.
    pub(crate) fn lock_for(&self, wait: Duration) -> io::Result<bool> {
        let deadline = SystemTime::now() + wait;
        let d = deadline.duration_since(UNIX_EPOCH).unwrap_or_default();
        let ts = libc::timespec {
            tv_sec: d.as_secs() as libc::time_t,
            tv_nsec: d.subsec_nanos() as libc::c_long,
        };
        // SAFETY: `ptr` maps an initialised process-shared mutex.
        match unsafe { libc::pthread_mutex_timedlock(self.ptr, &ts) } {
            0 => Ok(true),
            libc::ETIMEDOUT => Ok(false),
            rc => Err(io::Error::from_raw_os_error(rc)),
        }
    }

    /// Locks without waiting; false if it is taken.
    pub(crate) fn try_lock(&self) -> bool {
        // SAFETY: as `lock_for`.
        unsafe { libc::pthread_mutex_trylock(self.ptr) == 0 }
    }

    /// Unlocks (also when another process locked it: the wait-data mutex is used as a
    /// binary semaphore, as C++ does).
    pub(crate) fn unlock(&self) {
        // SAFETY: as `lock_for`; glibc's default mutex type accepts this.
        unsafe {
            libc::pthread_mutex_unlock(self.ptr);
        }
    }
}

impl Drop for ProcessMutex {
    fn drop(&mut self) {
        // SAFETY: `ptr` is our mapping of MUTEX_LEN bytes, unmapped once.
        unsafe {
            libc::munmap(self.ptr.cast(), MUTEX_LEN);
        }
        if let Some(path) = &self.owned {
            let _ = std::fs::remove_file(path);
        }
    }
}

fn open(path: &Path, flags: libc::c_int) -> io::Result<libc::c_int> {
    let c = CString::new(path.as_os_str().as_encoded_bytes())
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "NUL in path"))?;
    // SAFETY: plain system call with a NUL-terminated path.
    let fd = unsafe { libc::open(c.as_ptr(), flags | libc::O_CLOEXEC, PERMS) };
    if fd < 0 {
        let e = io::Error::last_os_error();
        return Err(io::Error::new(e.kind(), format!("{}: {e}", path.display())));
    }
    Ok(fd)
}

/// Maps a mutex file shared and closes the descriptor; null on failure.
///
/// # Safety
/// `fd` must be an open descriptor of a file at least `MUTEX_LEN` bytes long.
unsafe fn map(fd: libc::c_int) -> *mut libc::pthread_mutex_t {
    // SAFETY: per the contract.
    unsafe {
        let p = libc::mmap(
            std::ptr::null_mut(),
            MUTEX_LEN,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_SHARED,
            fd,
            0,
        );
        libc::close(fd);
        if p == libc::MAP_FAILED {
            std::ptr::null_mut()
        } else {
            p.cast()
        }
    }
}
