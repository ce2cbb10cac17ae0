//! The key list: every key and value a registration writes (the table in the module documentation),
//! derived from a [`ServerDescription`].

use super::description::ServerDescription;
use crate::com::HRESULT;
use crate::registry::cmdline::{command_line_of, program_path};
use crate::registry::sddl::sddl_to_bytes;
use crate::registry::{class_categories_key, class_key, RegValue, MAX_NAME_UNITS};

/// `REG_BINARY`.
const REG_BINARY: u32 = 3;

impl ServerDescription {
    pub(super) fn module_key(&self) -> String {
        let kind = if self.local { "LocalServer32" } else { "InprocServer32" };
        format!("{}\\{kind}", class_key(&self.clsid))
    }

    /// The module key a server of the other packaging would use.
    pub(super) fn other_module_key(&self) -> String {
        let kind = if self.local { "InprocServer32" } else { "LocalServer32" };
        format!("{}\\{kind}", class_key(&self.clsid))
    }

    /// The values registration writes: (key, value name, data, always replaced).
    pub(super) fn values(&self) -> Result<Vec<(String, String, RegValue, bool)>, HRESULT> {
        let mut v: Vec<(String, String, RegValue, bool)> = self
            .text_values()?
            .into_iter()
            .map(|(key, name, data, ours)| (key, name, RegValue::Sz(data), ours))
            .collect();
        if let Some(app_id) = &self.app_id {
            // The AppID's security, after its text values (see the module documentation).
            let app = format!("AppID\\{app_id}");
            v.push((
                app.clone(),
                "AuthenticationLevel".into(),
                RegValue::Dword(self.authentication_level()),
                false,
            ));
            for (name, sddl) in [
                ("AccessPermission", &self.access_permission),
                ("LaunchPermission", &self.launch_permission),
            ] {
                if let Some(sddl) = sddl {
                    let bytes = sddl_to_bytes(sddl)?;
                    v.push((
                        app.clone(),
                        name.into(),
                        RegValue::Other {
                            kind: REG_BINARY,
                            bytes,
                        },
                        false,
                    ));
                }
            }
        }
        Ok(v)
    }

    /// The string values registration writes: (key, value name, data, always replaced).
    fn text_values(&self) -> Result<Vec<(String, String, String, bool)>, HRESULT> {
        let class = class_key(&self.clsid);
        let clsid = self.clsid.to_string();
        let mut v = vec![(class.clone(), String::new(), self.user_type.clone(), false)];
        v.push((format!("{class}\\ProgID"), String::new(), self.prog_id.clone(), false));
        if let Some(vi) = &self.version_independent_prog_id {
            v.push((
                format!("{class}\\VersionIndependentProgID"),
                String::new(),
                vi.clone(),
                false,
            ));
        }
        let module = self.module_key();
        // An EXE server's module key holds a command line: the path quoted (CWE-428). An in-process
        // server's holds a plain file path, which COM loads as it is.
        let module_path = self.module_path()?;
        let module_value = if self.local {
            command_line_of(&module_path)
        } else {
            module_path
        };
        v.push((module.clone(), String::new(), module_value, true));
        if let (false, Some(tm)) = (self.local, &self.threading_model) {
            v.push((module, "ThreadingModel".into(), tm.clone(), true));
        }
        v.push((self.prog_id.clone(), String::new(), self.user_type.clone(), false));
        v.push((format!("{}\\CLSID", self.prog_id), String::new(), clsid.clone(), false));
        if let Some(vendor) = &self.da10_vendor {
            v.push((
                format!("{}\\OPC\\Vendor", self.prog_id),
                String::new(),
                vendor.clone(),
                false,
            ));
        }
        if let Some(vi) = &self.version_independent_prog_id {
            v.push((vi.clone(), String::new(), self.user_type.clone(), false));
            v.push((format!("{vi}\\CLSID"), String::new(), clsid.clone(), false));
            v.push((format!("{vi}\\CurVer"), String::new(), self.prog_id.clone(), false));
        }
        if let Some(app_id) = &self.app_id {
            let app = format!("AppID\\{app_id}");
            v.push((class.clone(), "AppID".into(), app_id.to_string(), false));
            v.push((app.clone(), String::new(), self.user_type.clone(), false));
            for (name, data) in [
                ("RunAs", &self.run_as),
                ("LocalService", &self.local_service),
                ("DllSurrogate", &self.dll_surrogate),
            ] {
                if let Some(data) = data {
                    v.push((app.clone(), name.into(), data.clone(), false));
                }
            }
            if let Some(exe) = self.app_id_program()? {
                v.push((format!("AppID\\{exe}"), "AppID".into(), app_id.to_string(), false));
            }
        }
        Ok(v)
    }

    /// The file name of an EXE server's program, for its `AppID\<exe>` key (none for an in-process
    /// server, or a name the registry cannot hold).
    pub(super) fn app_id_program(&self) -> Result<Option<String>, HRESULT> {
        if !self.local {
            return Ok(None);
        }
        let exe = program_file_name(&self.module_path()?).to_string();
        Ok((!exe.is_empty() && exe.encode_utf16().count() <= MAX_NAME_UNITS).then_some(exe))
    }

    /// The keys that belong to this server alone (deleted when empty even without a ledger).
    pub(super) fn own_keys(&self) -> Vec<String> {
        let class = class_key(&self.clsid);
        let mut keys = vec![
            class.clone(),
            format!("{class}\\ProgID"),
            format!("{class}\\VersionIndependentProgID"),
            self.module_key(),
            class_categories_key(&self.clsid, false),
            class_categories_key(&self.clsid, true),
            self.prog_id.clone(),
            format!("{}\\CLSID", self.prog_id),
            format!("{}\\OPC", self.prog_id),
            format!("{}\\OPC\\Vendor", self.prog_id),
        ];
        for (catid, _) in &self.implemented {
            keys.push(format!("{}\\{catid}", class_categories_key(&self.clsid, false)));
        }
        for catid in &self.required {
            keys.push(format!("{}\\{catid}", class_categories_key(&self.clsid, true)));
        }
        if let Some(vi) = &self.version_independent_prog_id {
            keys.extend([vi.clone(), format!("{vi}\\CLSID"), format!("{vi}\\CurVer")]);
        }
        if let Some(app_id) = &self.app_id {
            keys.push(format!("AppID\\{app_id}"));
        }
        keys
    }
}

/// The file name of the program a command line (a `LocalServer32` value) starts.
pub(super) fn program_file_name(command_line: &str) -> &str {
    let path = program_path(command_line);
    path.rsplit(['\\', '/']).next().unwrap_or(path)
}
