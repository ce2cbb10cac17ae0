//! The Windows registry under `HKEY_CLASSES_ROOT`, in one registry view, and the Component Categories
//! Manager (ICatRegister) through which categories are registered, as specification section 6.1.1
//! asks.
//!
//! On 64-bit Windows a 32-bit server registers in the 32-bit view (`WOW6432Node`) and a 64-bit one in
//! the 64-bit view; a client only sees its own view unless it looks at both. The server list therefore
//! reads both views (`KEY_WOW64_64KEY` and `KEY_WOW64_32KEY`), native first. On 32-bit Windows both
//! flags are ignored and the two views are the same registry (duplicates are removed by the server
//! list).

use core::ffi::c_void;
use core::ptr;
use std::sync::atomic::{AtomicBool, Ordering::SeqCst};
use std::sync::{Arc, OnceLock};

use windows_sys::Win32::Foundation::{
    CloseHandle, ERROR_FILE_NOT_FOUND, ERROR_MORE_DATA, ERROR_NO_MORE_ITEMS, ERROR_SUCCESS, HANDLE, HMODULE,
    WAIT_TIMEOUT, WIN32_ERROR,
};
use windows_sys::Win32::System::Com::{CoCreateInstance, CLSCTX_INPROC_SERVER};
use windows_sys::Win32::System::LibraryLoader::{
    GetModuleFileNameW, GetModuleHandleExW, GetModuleHandleW, GetProcAddress, GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS,
    GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT,
};
use windows_sys::Win32::System::Registry::{
    RegCloseKey, RegCreateKeyExW, RegDeleteKeyExW, RegDeleteValueW, RegEnumKeyExW, RegEnumValueW,
    RegNotifyChangeKeyValue, RegOpenKeyExW, RegQueryValueExW, RegSetValueExW, HKEY, HKEY_CLASSES_ROOT,
    HKEY_CURRENT_USER, HKEY_LOCAL_MACHINE, KEY_NOTIFY, KEY_QUERY_VALUE, KEY_READ, KEY_SET_VALUE, KEY_WOW64_32KEY,
    KEY_WOW64_64KEY, KEY_WRITE, REG_DWORD, REG_EXPAND_SZ, REG_NOTIFY_CHANGE_LAST_SET, REG_NOTIFY_CHANGE_NAME,
    REG_NOTIFY_THREAD_AGNOSTIC, REG_OPTION_NON_VOLATILE, REG_SZ,
};
use windows_sys::Win32::System::SystemServices::MAXIMUM_ALLOWED;
use windows_sys::Win32::System::Threading::{CreateEventW, ResetEvent, WaitForMultipleObjects};

use super::watch::ChangeWatch;
use super::{class_category_key, class_key, write_category, ClassStrings, RegValue, Registries, Registry};
use crate::com::interfaces::ICatRegister;
use crate::com::unknown::Counted;
use crate::com::{CATEGORYINFO, E_FAIL, GUID, HRESULT};

/// `HRESULT_FROM_WIN32`.
fn hr_from_win32(e: WIN32_ERROR) -> HRESULT {
    if e == ERROR_SUCCESS {
        0
    } else {
        ((e & 0xFFFF) | 0x8007_0000) as HRESULT
    }
}

fn wide(s: &str) -> Vec<u16> {
    s.encode_utf16().chain([0]).collect()
}

/// An open registry key, closed when dropped.
struct Key(HKEY);

// SAFETY: a registry handle may be used and closed from any thread; `Key` only passes it to the
// registry functions.
unsafe impl Send for Key {}
// SAFETY: as above: the registry functions may be called on one handle from several threads.
unsafe impl Sync for Key {}

impl Drop for Key {
    fn drop(&mut self) {
        // SAFETY: the handle was opened by this module and is closed once.
        unsafe { RegCloseKey(self.0) };
    }
}

impl Key {
    fn subkeys(&self) -> Vec<String> {
        let mut names = Vec::new();
        let mut buf = [0u16; 256];
        for index in 0.. {
            let mut len = buf.len() as u32;
            // SAFETY: `buf` has room for `len` units; the other outputs are optional.
            let e = unsafe {
                RegEnumKeyExW(
                    self.0,
                    index,
                    buf.as_mut_ptr(),
                    &mut len,
                    ptr::null(),
                    ptr::null_mut(),
                    ptr::null_mut(),
                    ptr::null_mut(),
                )
            };
            if e != ERROR_SUCCESS {
                break;
            }
            names.push(String::from_utf16_lossy(&buf[..len as usize]));
        }
        names
    }

    fn open(&self, sub: &str, access: u32) -> Option<Key> {
        let mut h: HKEY = ptr::null_mut();
        // SAFETY: valid handle and NUL-terminated name; `h` is written on success.
        let e = unsafe { RegOpenKeyExW(self.0, wide(sub).as_ptr(), 0, access, &mut h) };
        (e == ERROR_SUCCESS).then_some(Key(h))
    }

    fn value(&self, name: &str) -> Option<RegValue> {
        let name = wide(name);
        let mut data: Vec<u8> = vec![0; 256];
        loop {
            let mut kind = 0u32;
            let mut len = data.len() as u32;
            // SAFETY: `data` has room for `len` bytes.
            let e = unsafe {
                RegQueryValueExW(
                    self.0,
                    name.as_ptr(),
                    ptr::null(),
                    &mut kind,
                    data.as_mut_ptr(),
                    &mut len,
                )
            };
            match e {
                ERROR_SUCCESS => {
                    data.truncate(len as usize);
                    return Some(convert(kind, data));
                }
                ERROR_MORE_DATA => data.resize(len as usize, 0),
                _ => return None,
            }
        }
    }

    fn values(&self) -> Vec<(String, RegValue)> {
        let mut out = Vec::new();
        let mut name = vec![0u16; 16384];
        let mut data: Vec<u8> = vec![0; 1024];
        let mut index = 0;
        loop {
            let mut name_len = name.len() as u32;
            let mut len = data.len() as u32;
            let mut kind = 0u32;
            // SAFETY: both buffers have the room their lengths say.
            let e = unsafe {
                RegEnumValueW(
                    self.0,
                    index,
                    name.as_mut_ptr(),
                    &mut name_len,
                    ptr::null(),
                    &mut kind,
                    data.as_mut_ptr(),
                    &mut len,
                )
            };
            match e {
                ERROR_SUCCESS => {
                    let value = convert(kind, data[..len as usize].to_vec());
                    out.push((String::from_utf16_lossy(&name[..name_len as usize]), value));
                    index += 1;
                }
                ERROR_MORE_DATA => data.resize((len as usize).max(data.len() * 2), 0),
                ERROR_NO_MORE_ITEMS => return out,
                _ => return out,
            }
        }
    }
}

/// A registry value's bytes as a [`RegValue`].
fn convert(kind: u32, bytes: Vec<u8>) -> RegValue {
    if kind == REG_SZ || kind == REG_EXPAND_SZ {
        if bytes.len() % 2 == 0 {
            let mut units: Vec<u16> = bytes.chunks(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
            while units.last() == Some(&0) {
                units.pop();
            }
            if let Ok(s) = String::from_utf16(&units) {
                return if kind == REG_SZ {
                    RegValue::Sz(s)
                } else {
                    RegValue::ExpandSz(s)
                };
            }
        }
    } else if kind == REG_DWORD && bytes.len() == 4 {
        return RegValue::Dword(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]));
    }
    RegValue::Other { kind, bytes }
}

/// True when the library runs under Wine (its ntdll exports `wine_get_version`).
fn under_wine() -> bool {
    static WINE: OnceLock<bool> = OnceLock::new();
    *WINE.get_or_init(|| {
        let ntdll = wide("ntdll.dll");
        // SAFETY: NUL-terminated names; ntdll is loaded in every process and stays loaded.
        unsafe {
            let module = GetModuleHandleW(ntdll.as_ptr());
            !module.is_null() && GetProcAddress(module, c"wine_get_version".as_ptr().cast()).is_some()
        }
    })
}

/// `HKEY_CLASSES_ROOT` in one registry view.
pub struct WindowsRegistry {
    /// `KEY_WOW64_64KEY`, `KEY_WOW64_32KEY`, or 0 for the view of the calling process.
    view: u32,
    /// Under Wine, for a view flag other than 0: the classes root opened once in that view, the key
    /// every path of the view is opened from. Wine gives every open from the predefined
    /// `HKEY_CLASSES_ROOT` with `KEY_WOW64_32KEY` or `KEY_WOW64_64KEY` a handle it never closes (one
    /// per read: a Wine-hosted browser grew by a handle per enumeration); opens relative to a key it
    /// opened cost none. Its `HKEY_CLASSES_ROOT` is `HKEY_LOCAL_MACHINE\Software\Classes`, so that key
    /// is opened. `None` inside (on Windows, or when the open failed): paths are opened from the
    /// predefined key.
    root: OnceLock<Option<Key>>,
}

impl WindowsRegistry {
    /// The registry view of the calling process (where registration writes).
    pub fn native() -> WindowsRegistry {
        WindowsRegistry::view(0)
    }

    /// `HKEY_CLASSES_ROOT` in the view `view` (`KEY_WOW64_64KEY`, `KEY_WOW64_32KEY` or 0).
    fn view(view: u32) -> WindowsRegistry {
        WindowsRegistry {
            view,
            root: OnceLock::new(),
        }
    }

    /// The key paths of this view are opened from (see `root`).
    fn root(&self) -> HKEY {
        if self.view == 0 {
            return HKEY_CLASSES_ROOT;
        }
        let root = self.root.get_or_init(|| {
            if !under_wine() {
                return None;
            }
            let mut h: HKEY = ptr::null_mut();
            let classes = wide("Software\\Classes");
            // SAFETY: predefined root, NUL-terminated path; `h` is written on success.
            let e = unsafe {
                RegOpenKeyExW(
                    HKEY_LOCAL_MACHINE,
                    classes.as_ptr(),
                    0,
                    MAXIMUM_ALLOWED | self.view,
                    &mut h,
                )
            };
            (e == ERROR_SUCCESS).then_some(Key(h))
        });
        root.as_ref().map_or(HKEY_CLASSES_ROOT, |k| k.0)
    }

    fn open(&self, path: &str, access: u32) -> Option<Key> {
        let mut h: HKEY = ptr::null_mut();
        // SAFETY: an open root, NUL-terminated path; `h` is written on success.
        let e = unsafe { RegOpenKeyExW(self.root(), wide(path).as_ptr(), 0, access | self.view, &mut h) };
        (e == ERROR_SUCCESS).then_some(Key(h))
    }

    fn create(&self, path: &str) -> Result<Key, HRESULT> {
        let mut h: HKEY = ptr::null_mut();
        // SAFETY: an open root, NUL-terminated path, optional arguments NULL; `h` written on success.
        let e = unsafe {
            RegCreateKeyExW(
                self.root(),
                wide(path).as_ptr(),
                0,
                ptr::null(),
                REG_OPTION_NON_VOLATILE,
                KEY_WRITE | self.view,
                ptr::null(),
                &mut h,
                ptr::null_mut(),
            )
        };
        if e == ERROR_SUCCESS {
            Ok(Key(h))
        } else {
            Err(hr_from_win32(e))
        }
    }

    /// The Component Categories Manager, when this is the process's own view and COM is initialised
    /// on the calling thread (else `None`: the caller writes the same keys itself).
    fn cat_register(&self) -> Option<Counted<ICatRegister>> {
        if self.view != 0 {
            return None;
        }
        let mut p: *mut c_void = ptr::null_mut();
        // SAFETY: constant GUIDs with the layout of windows-sys' GUID; `p` is written on success.
        let hr = unsafe {
            CoCreateInstance(
                (&CLSID_STD_COMPONENT_CATEGORIES_MGR as *const GUID).cast(),
                ptr::null_mut(),
                CLSCTX_INPROC_SERVER,
                (&ICatRegister::IID as *const GUID).cast(),
                &mut p,
            )
        };
        if hr < 0 {
            // CO_E_NOTINITIALIZED without COM; a pointer left behind with a failure is not trusted.
            return None;
        }
        // SAFETY: a successful CoCreateInstance hands over one reference (NULL gives None).
        unsafe { Counted::adopt(p.cast::<ICatRegister>()) }
    }
}

impl Registry for WindowsRegistry {
    fn key_exists(&self, path: &str) -> bool {
        self.open(path, KEY_READ).is_some()
    }

    fn subkeys(&self, path: &str) -> Vec<String> {
        self.open(path, KEY_READ).map(|k| k.subkeys()).unwrap_or_default()
    }

    fn values(&self, path: &str) -> Vec<(String, RegValue)> {
        self.open(path, KEY_READ).map(|k| k.values()).unwrap_or_default()
    }

    fn value(&self, path: &str, name: &str) -> Option<RegValue> {
        self.open(path, KEY_READ)?.value(name)
    }

    fn create_key(&self, path: &str) -> Result<(), HRESULT> {
        self.create(path).map(drop)
    }

    fn set_value(&self, path: &str, name: &str, value: &RegValue) -> Result<(), HRESULT> {
        let key = self.create(path)?;
        let (kind, bytes): (u32, Vec<u8>) = match value {
            RegValue::Sz(s) => (REG_SZ, wide(s).iter().flat_map(|u| u.to_le_bytes()).collect()),
            RegValue::ExpandSz(s) => (REG_EXPAND_SZ, wide(s).iter().flat_map(|u| u.to_le_bytes()).collect()),
            RegValue::Dword(d) => (REG_DWORD, d.to_le_bytes().to_vec()),
            RegValue::Other { kind, bytes } => (*kind, bytes.clone()),
        };
        let len = u32::try_from(bytes.len()).map_err(|_| crate::com::E_INVALIDARG)?;
        // SAFETY: open key, NUL-terminated name, `bytes` holds `len` bytes.
        let e = unsafe { RegSetValueExW(key.0, wide(name).as_ptr(), 0, kind, bytes.as_ptr(), len) };
        if e == ERROR_SUCCESS {
            Ok(())
        } else {
            Err(hr_from_win32(e))
        }
    }

    fn delete_value(&self, path: &str, name: &str) -> Result<(), HRESULT> {
        let Some(key) = self.open(path, KEY_SET_VALUE) else {
            return Ok(());
        };
        // SAFETY: open key, NUL-terminated name.
        let e = unsafe { RegDeleteValueW(key.0, wide(name).as_ptr()) };
        match e {
            ERROR_SUCCESS | ERROR_FILE_NOT_FOUND => Ok(()),
            e => Err(hr_from_win32(e)),
        }
    }

    fn delete_key(&self, path: &str) -> Result<(), HRESULT> {
        if path.is_empty() {
            return Err(crate::com::E_INVALIDARG);
        }
        // SAFETY: an open root, NUL-terminated path. Fails with access denied when subkeys exist.
        let e = unsafe { RegDeleteKeyExW(self.root(), wide(path).as_ptr(), self.view, 0) };
        match e {
            ERROR_SUCCESS | ERROR_FILE_NOT_FOUND => Ok(()),
            e => Err(hr_from_win32(e)),
        }
    }

    /// One open of `parent`, then one relative open per child: several times faster than opening
    /// every path from the root.
    fn scan(&self, parent: &str, children: &[&str]) -> Vec<(String, Vec<Option<Vec<String>>>)> {
        let Some(parent_key) = self.open(parent, KEY_READ) else {
            return Vec::new();
        };
        parent_key
            .subkeys()
            .into_iter()
            .map(|name| {
                let found = children
                    .iter()
                    .map(|child| {
                        parent_key
                            .open(&format!("{name}\\{child}"), KEY_READ | self.view)
                            .map(|k| k.subkeys())
                    })
                    .collect();
                (name, found)
            })
            .collect()
    }

    /// One open of `parent`, then one relative open per subkey, as `scan`.
    fn subkey_values(&self, parent: &str, name: &str) -> Vec<(String, RegValue)> {
        let Some(parent_key) = self.open(parent, KEY_READ) else {
            return Vec::new();
        };
        parent_key
            .subkeys()
            .into_iter()
            .filter_map(|sub| {
                let value = parent_key.open(&sub, KEY_QUERY_VALUE | self.view)?.value(name)?;
                Some((sub, value))
            })
            .collect()
    }

    /// One open of the class key from the root, then relative opens: the fewest registry calls.
    fn class_strings(&self, clsid: &GUID, version_independent: bool) -> Option<ClassStrings> {
        let class = self.open(&class_key(clsid), KEY_READ)?;
        let text = |v: Option<RegValue>| v.and_then(|v| v.as_str().map(str::to_string));
        let sub = |name: &str| text(class.open(name, KEY_QUERY_VALUE | self.view).and_then(|k| k.value("")));
        Some(ClassStrings {
            user_type: text(class.value("")),
            prog_id: sub("ProgID"),
            version_independent_prog_id: if version_independent {
                sub("VersionIndependentProgID")
            } else {
                None
            },
        })
    }

    fn register_category(&self, catid: &GUID, lcid: u32, description: &str) -> Result<(), HRESULT> {
        let Some(cats) = self.cat_register() else {
            return write_category(self, catid, lcid, description);
        };
        let mut info = CATEGORYINFO {
            catid: *catid,
            lcid,
            szDescription: [0; 128],
        };
        for (slot, unit) in info.szDescription.iter_mut().zip(description.encode_utf16().take(127)) {
            *slot = unit;
        }
        // SAFETY: live ICatRegister; one CATEGORYINFO.
        let hr = unsafe { ICatRegister::RegisterCategories(cats.as_ptr(), 1, &mut info) };
        ok(hr)
    }

    fn register_class_category(&self, clsid: &GUID, catid: &GUID, required: bool) -> Result<(), HRESULT> {
        let Some(cats) = self.cat_register() else {
            return self.create_key(&class_category_key(clsid, catid, required));
        };
        let mut id = *catid;
        // SAFETY: live ICatRegister; one CATID.
        let hr = unsafe {
            if required {
                ICatRegister::RegisterClassReqCategories(cats.as_ptr(), clsid, 1, &mut id)
            } else {
                ICatRegister::RegisterClassImplCategories(cats.as_ptr(), clsid, 1, &mut id)
            }
        };
        ok(hr)
    }

    fn unregister_class_category(&self, clsid: &GUID, catid: &GUID, required: bool) -> Result<(), HRESULT> {
        let Some(cats) = self.cat_register() else {
            return self.delete_key(&class_category_key(clsid, catid, required));
        };
        let mut id = *catid;
        // SAFETY: live ICatRegister; one CATID.
        let hr = unsafe {
            if required {
                ICatRegister::UnRegisterClassReqCategories(cats.as_ptr(), clsid, 1, &mut id)
            } else {
                ICatRegister::UnRegisterClassImplCategories(cats.as_ptr(), clsid, 1, &mut id)
            }
        };
        ok(hr)
    }
}

fn ok(hr: HRESULT) -> Result<(), HRESULT> {
    if hr < 0 {
        Err(hr)
    } else {
        Ok(())
    }
}

/// A manual-reset event, closed when dropped.
struct Event(HANDLE);

// SAFETY: an event handle may be waited on, reset and closed from any thread.
unsafe impl Send for Event {}
// SAFETY: as above.
unsafe impl Sync for Event {}

impl Drop for Event {
    fn drop(&mut self) {
        // SAFETY: the handle was created by `Event::new` and is closed once.
        unsafe { CloseHandle(self.0) };
    }
}

impl Event {
    /// A manual-reset event, signalled to start with (a watch not armed yet has "seen a change").
    fn new() -> Result<Event, HRESULT> {
        // SAFETY: no attributes, no name.
        let h = unsafe { CreateEventW(ptr::null(), 1, 1, ptr::null()) };
        if h.is_null() {
            Err(E_FAIL)
        } else {
            Ok(Event(h))
        }
    }
}

/// One key watched with its own event.
struct Watched {
    key: Key,
    event: Event,
    /// A notification is pending on `key` (armed and not yet signalled).
    armed: AtomicBool,
}

/// The change watch of the system registry: a registry change notification
/// (`RegNotifyChangeKeyValue`, the whole subtree, names and values) on the classes the server list
/// reads, in each view it reads: `HKEY_LOCAL_MACHINE\Software\Classes` (what Wine's
/// `HKEY_CLASSES_ROOT` is) and, where there is one, `HKEY_CURRENT_USER\Software\Classes` (which
/// Windows merges into `HKEY_CLASSES_ROOT`), each with its own manual-reset event. The registry
/// signals an event in the same operation as the change it reports (a change by another process
/// is seen by the next check). `changed` asks every event at once without waiting; `arm` arms again
/// only the keys whose notification has fired, so no key gathers pending notifications.
pub(crate) struct ClassesWatch {
    /// The view flags of the views read.
    views: Vec<u32>,
    /// Opened on the first arm that could open them.
    keys: OnceLock<Vec<Watched>>,
    /// The notification's thread-agnostic flag, dropped after Windows 7 refused it (there the
    /// notification ends, signalled, when the thread that armed it ends: one scan more).
    agnostic: AtomicBool,
}

impl ClassesWatch {
    fn new(views: Vec<u32>) -> ClassesWatch {
        ClassesWatch {
            views,
            keys: OnceLock::new(),
            agnostic: AtomicBool::new(true),
        }
    }

    fn open(root: HKEY, view: u32) -> Option<Key> {
        let mut h: HKEY = ptr::null_mut();
        let path = wide("Software\\Classes");
        // SAFETY: predefined root, NUL-terminated path; `h` is written on success.
        let e = unsafe { RegOpenKeyExW(root, path.as_ptr(), 0, KEY_NOTIFY | view, &mut h) };
        (e == ERROR_SUCCESS).then_some(Key(h))
    }

    /// The watched keys, opened once: the machine's classes in every view must open, the user's are
    /// watched where they exist.
    fn keys(&self) -> Result<&[Watched], HRESULT> {
        if let Some(keys) = self.keys.get() {
            return Ok(keys);
        }
        let mut keys = Vec::new();
        for &view in &self.views {
            let machine = Self::open(HKEY_LOCAL_MACHINE, view).ok_or(E_FAIL)?;
            for key in [Some(machine), Self::open(HKEY_CURRENT_USER, view)]
                .into_iter()
                .flatten()
            {
                keys.push(Watched {
                    key,
                    event: Event::new()?,
                    armed: AtomicBool::new(false),
                });
            }
        }
        Ok(self.keys.get_or_init(|| keys))
    }

    fn notify(&self, w: &Watched) -> WIN32_ERROR {
        let filter = REG_NOTIFY_CHANGE_NAME | REG_NOTIFY_CHANGE_LAST_SET;
        let notify = |filter| {
            // SAFETY: an open key and event; asynchronous, so the call returns at once.
            unsafe { RegNotifyChangeKeyValue(w.key.0, 1, filter, w.event.0, 1) }
        };
        if self.agnostic.load(SeqCst) {
            let e = notify(filter | REG_NOTIFY_THREAD_AGNOSTIC);
            if e != windows_sys::Win32::Foundation::ERROR_INVALID_PARAMETER {
                return e;
            }
            self.agnostic.store(false, SeqCst);
        }
        notify(filter)
    }
}

impl ChangeWatch for ClassesWatch {
    fn arm(&self) -> Result<(), HRESULT> {
        let mut result = Ok(());
        for w in self.keys()? {
            // SAFETY: an open event; a zero timeout only asks.
            let fired = unsafe { WaitForMultipleObjects(1, &w.event.0, 0, 0) } != WAIT_TIMEOUT;
            if w.armed.load(SeqCst) && !fired {
                continue; // still pending: it reports the next change
            }
            w.armed.store(false, SeqCst);
            // Reset before the notification is asked for: a change in between is read by the scan
            // that follows the arm.
            // SAFETY: an open event.
            unsafe { ResetEvent(w.event.0) };
            match self.notify(w) {
                ERROR_SUCCESS => w.armed.store(true, SeqCst),
                e => {
                    // Signalled again: `changed` answers true until an arm succeeds.
                    // SAFETY: an open event.
                    unsafe { windows_sys::Win32::System::Threading::SetEvent(w.event.0) };
                    result = Err(hr_from_win32(e));
                }
            }
        }
        result
    }

    fn changed(&self) -> bool {
        let Some(keys) = self.keys.get() else { return true };
        // (Two keys per view, two views.)
        let mut events = [ptr::null_mut(); 8];
        for (slot, w) in events.iter_mut().zip(keys) {
            *slot = w.event.0;
        }
        let count = keys.len().min(events.len());
        // SAFETY: `count` open events (below MAXIMUM_WAIT_OBJECTS); a zero timeout only asks.
        let r = unsafe { WaitForMultipleObjects(count as u32, events.as_ptr(), 0, 0) };
        // Any event signalled, or a failure to ask: changed.
        r != WAIT_TIMEOUT
    }
}

/// The registries of the system: writes go to the process's own view, reads merge both views.
pub(crate) fn system_registries() -> Registries {
    let native: Arc<dyn Registry> = Arc::new(WindowsRegistry::native());
    // The process's own view first (flag 0: the cheapest opens), then the other one.
    let (first, second) = if cfg!(target_pointer_width = "64") {
        (0, KEY_WOW64_32KEY)
    } else {
        (0, KEY_WOW64_64KEY)
    };
    Registries::new(
        native,
        vec![
            Arc::new(WindowsRegistry::view(first)),
            Arc::new(WindowsRegistry::view(second)),
        ],
        Box::new(ClassesWatch::new(vec![first, second])),
    )
}

/// The module (DLL or EXE) that contains this code, without taking a reference on it. Found from an
/// address rather than kept by a DllMain, because a program linking the library statically may have
/// its own DllMain.
pub(crate) fn this_module() -> HMODULE {
    let mut h: HMODULE = ptr::null_mut();
    // SAFETY: the address of a function in this module; `h` is written on success.
    let ok = unsafe {
        GetModuleHandleExW(
            GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS | GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT,
            this_module as *const () as *const u16,
            &mut h,
        )
    };
    if ok == 0 {
        ptr::null_mut()
    } else {
        h
    }
}

/// The full path of `module` (NULL: the executable of the process).
pub(crate) fn module_file_name(module: HMODULE) -> Result<String, HRESULT> {
    let mut buf = vec![0u16; 260];
    loop {
        // SAFETY: `buf` has room for `buf.len()` units.
        let n = unsafe { GetModuleFileNameW(module, buf.as_mut_ptr(), buf.len() as u32) } as usize;
        if n == 0 {
            return Err(E_FAIL);
        }
        if n < buf.len() {
            return String::from_utf16(&buf[..n]).map_err(|_| E_FAIL);
        }
        if buf.len() >= 32768 {
            return Err(E_FAIL);
        }
        buf.resize(buf.len() * 2, 0);
    }
}

/// `CLSID_StdComponentCategoriesMgr` {0002E005-0000-0000-C000-000000000046}.
const CLSID_STD_COMPONENT_CATEGORIES_MGR: GUID = GUID::from_u128(0x0002E005_0000_0000_C000_000000000046);

#[cfg(test)]
mod tests {
    use super::*;

    const SCRATCH: &str = "OpcComn.Test.Scratch";

    #[test]
    fn the_windows_registry_behaves_like_the_memory_one() {
        let reg = WindowsRegistry::native();
        let _ = reg.delete_key(&format!("{SCRATCH}\\Sub\\Leaf"));
        let _ = reg.delete_key(&format!("{SCRATCH}\\Sub"));
        let _ = reg.delete_key(SCRATCH);
        reg.set_value(&format!("{SCRATCH}\\Sub"), "", &RegValue::Sz("text".into()))
            .unwrap();
        reg.set_value(&format!("{SCRATCH}\\Sub"), "N", &RegValue::Dword(7))
            .unwrap();
        reg.create_key(&format!("{SCRATCH}\\Sub\\Leaf")).unwrap();
        assert!(reg.key_exists(&format!("{}\\sub", SCRATCH.to_uppercase())));
        assert_eq!(
            reg.value(&format!("{SCRATCH}\\Sub"), ""),
            Some(RegValue::Sz("text".into()))
        );
        let mut values = reg.values(&format!("{SCRATCH}\\Sub"));
        values.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(
            values,
            vec![
                (String::new(), RegValue::Sz("text".into())),
                ("N".into(), RegValue::Dword(7))
            ]
        );
        assert_eq!(
            reg.scan(SCRATCH, &["Leaf", "Missing"]),
            vec![("Sub".to_string(), vec![Some(vec![]), None])]
        );
        // A key with subkeys is not deleted.
        assert!(reg.delete_key(&format!("{SCRATCH}\\Sub")).is_err());
        reg.delete_value(&format!("{SCRATCH}\\Sub"), "N").unwrap();
        reg.delete_value(&format!("{SCRATCH}\\Sub"), "N").unwrap();
        reg.delete_key(&format!("{SCRATCH}\\Sub\\Leaf")).unwrap();
        reg.delete_key(&format!("{SCRATCH}\\Sub")).unwrap();
        reg.delete_key(SCRATCH).unwrap();
        assert!(!reg.key_exists(SCRATCH));
        assert!(reg.delete_key(SCRATCH).is_ok());
    }

    #[test]
    fn the_other_view_is_separate_for_classes() {
        let key = "CLSID\\{C3000000-0000-4000-8000-000000000001}";
        let native = WindowsRegistry::native();
        // The view of the other bitness: the 32-bit view from a 64-bit process, the 64-bit view from a
        // 32-bit process under WOW64.
        let (other_view, text) = if cfg!(target_pointer_width = "64") {
            (KEY_WOW64_32KEY, "32-bit only")
        } else {
            (KEY_WOW64_64KEY, "64-bit only")
        };
        let other = WindowsRegistry::view(other_view);
        // What an earlier failed run may have left behind.
        let _ = native.delete_key(key);
        let _ = other.delete_key(key);
        other.set_value(key, "", &RegValue::Sz(text.into())).unwrap();
        assert!(other.key_exists(key));
        assert!(!native.key_exists(key), "a process sees its own view under HKCR\\CLSID");
        let regs = system_registries();
        let clsid = super::super::parse_guid(&key[6..]).unwrap();
        let found = regs.views.iter().find_map(|v| v.class_strings(&clsid, false));
        assert_eq!(found.and_then(|s| s.user_type).as_deref(), Some(text));
        other.delete_key(key).unwrap();
        assert!(!other.key_exists(key));
    }

    #[test]
    fn a_change_of_the_classes_in_either_view_signals_the_watch() {
        let other_view = if cfg!(target_pointer_width = "64") {
            KEY_WOW64_32KEY
        } else {
            KEY_WOW64_64KEY
        };
        let watch = ClassesWatch::new(vec![0, other_view]);
        assert!(watch.changed(), "not armed yet");
        for (view, n) in [(0, 1u128), (other_view, 2)] {
            let reg = WindowsRegistry::view(view);
            let key = format!(
                "CLSID\\{}\\Implemented Categories\\{}",
                GUID::from_u128(0xC3100000_0000_4000_8000_000000000000 + n),
                crate::registry::categories::CATID_OPCDAServer20
            );
            // Other tests of this process write the registry meanwhile: a quiet moment is enough.
            let quiet = (0..200).any(|_| {
                watch.arm().unwrap();
                !watch.changed() || {
                    std::thread::sleep(std::time::Duration::from_millis(5));
                    false
                }
            });
            assert!(quiet, "the watch never stayed quiet once armed");
            // A key deep below CLSID, written by this process: seen by the very next check.
            reg.create_key(&key).unwrap();
            assert!(watch.changed(), "view {view:#x}: a new key");
            watch.arm().unwrap();
            for parent in [
                key.as_str(),
                &key[..key.rfind('\\').unwrap()],
                &key[..key.find("\\Impl").unwrap()],
            ] {
                reg.delete_key(parent).unwrap();
            }
            assert!(watch.changed(), "view {view:#x}: keys deleted");
            assert!(!reg.key_exists(&key[..key.find("\\Impl").unwrap()]));
        }
    }

    #[test]
    fn reading_the_other_view_costs_no_handle() {
        use windows_sys::Win32::Foundation::{GetHandleInformation, HANDLE};
        // The handles of this process, counted by asking each possible value (Wine's
        // GetProcessHandleCount says 0).
        let open_handles = || {
            (1..16384usize)
                .filter(|slot| {
                    let mut flags = 0u32;
                    // SAFETY: asks about a handle value; an invalid one fails without effect.
                    unsafe { GetHandleInformation((slot * 4) as HANDLE, &mut flags) != 0 }
                })
                .count()
        };
        let regs = system_registries();
        // The kinds of reads a server-list enumeration and GetClassDetails make, in both views.
        let browse = || {
            for view in &regs.views {
                let _ = view.scan("Component Categories", &["Missing"]);
                let _ = view.class_strings(&GUID::from_u128(1), true);
                let _ = view.key_exists("CLSID");
                let _ = view.value("CLSID", "");
            }
        };
        browse();
        // Other tests of this process open and close handles meanwhile (threads, events, keys),
        // sometimes hundreds at once: a leak of a handle per read grows the count by 300 or more
        // in every attempt, that noise only in some. Up to five attempts; one under the margin
        // passes.
        let mut seen = Vec::new();
        for _ in 0..5 {
            let before = open_handles();
            for _ in 0..300 {
                browse();
            }
            let after = open_handles();
            if after < before + 50 {
                return;
            }
            seen.push((before, after));
        }
        panic!("handles (before, after) in each attempt: {seen:?}");
    }
}
