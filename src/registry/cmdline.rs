//! The command line of an EXE server (specification section 6.3): `/RegServer` or `-RegServer` asks it
//! to register itself, `/UnregServer` or `-UnregServer` to unregister, and COM starts it with
//! `-Embedding` (or `/Embedding`; `-Automation` for automation servers) to serve its classes.

use crate::com::ffi::{self, Hr};
use crate::com::{E_INVALIDARG, HRESULT, LPCWSTR, S_OK};

/// What an EXE server's command line asks it to do.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpcServerCommand {
    /// No switch the library knows: the server was started by hand.
    None = 0,
    /// `/RegServer` or `-RegServer`: register and exit.
    Register = 1,
    /// `/UnregServer` or `-UnregServer`: unregister and exit.
    Unregister = 2,
    /// `-Embedding`, `/Embedding`, `-Automation` or `/Automation`: COM started the server for a client.
    Embedding = 3,
}

/// The command line that starts the program at `path` (a `LocalServer32` value): the path in double
/// quotes, so that a path with blanks cannot be read as a shorter program plus arguments
/// (`C:\Program Files\OPC Tools\x.exe` unquoted runs `C:\Program.exe` or `C:\Program Files\OPC.exe`
/// when such a file exists, CWE-428). A path that already holds a quote is a command line its caller
/// wrote (a path cannot contain `"`) and is kept as given.
pub(crate) fn command_line_of(path: &str) -> String {
    if path.contains('"') {
        path.to_string()
    } else {
        format!("\"{path}\"")
    }
}

/// The program path of a command line as `LocalServer32` holds it: the text between the leading pair
/// of quotes, or (unquoted, as older registrations wrote it) the whole text.
pub(crate) fn program_path(command_line: &str) -> &str {
    let line = command_line.trim_start();
    match line.strip_prefix('"') {
        Some(rest) => rest.split('"').next().unwrap_or(rest),
        None => line.trim_end(),
    }
}

/// Splits a command line into arguments the way Windows programs do for the cases that matter here:
/// blanks separate arguments, double quotes group blanks into one.
pub(crate) fn arguments(line: &str) -> Vec<String> {
    let mut args = Vec::new();
    let mut current = String::new();
    let mut quoted = false;
    let mut any = false;
    for c in line.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                any = true;
            }
            ' ' | '\t' if !quoted => {
                if any {
                    args.push(core::mem::take(&mut current));
                    any = false;
                }
            }
            c => {
                current.push(c);
                any = true;
            }
        }
    }
    if any {
        args.push(current);
    }
    args
}

/// What `line` asks for. Switches are matched without regard to case, anywhere on the line (so the
/// program name may come first or not); other arguments are ignored. Asking to register and to
/// unregister at once is an error.
pub fn parse_command_line(line: &str) -> Result<OpcServerCommand, HRESULT> {
    let mut register = false;
    let mut unregister = false;
    let mut embedding = false;
    for arg in arguments(line) {
        let Some(switch) = arg.strip_prefix(['/', '-']) else {
            continue;
        };
        let switch = switch.to_ascii_lowercase();
        match switch.as_str() {
            "regserver" => register = true,
            "unregserver" => unregister = true,
            "embedding" | "automation" => embedding = true,
            _ => {}
        }
    }
    Ok(match (register, unregister) {
        (true, true) => return Err(E_INVALIDARG),
        (true, false) => OpcServerCommand::Register,
        (false, true) => OpcServerCommand::Unregister,
        _ if embedding => OpcServerCommand::Embedding,
        _ => OpcServerCommand::None,
    })
}

/// Tells what an EXE server's command line asks for: `/RegServer` or `-RegServer`, `/UnregServer` or
/// `-UnregServer`, `-Embedding` or `/Embedding` (and `-Automation`), case-insensitive, as separate
/// arguments. `OpcExeServerRun` does this itself; this is for a `main` of your own.
///
/// # Parameters
/// - `command_line`: the command line, with or without the program name (`GetCommandLineW()`).
/// - `command` (out): receives an `OpcServerCommand` value (register, unregister, embedding or none);
///   OPC_SERVER_COMMAND_NONE on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL argument; E_INVALIDARG when the line both registers and unregisters or
/// is not valid UTF-16.
///
/// # Safety
/// `command_line` NULL or NUL-terminated; `command` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcParseCommandLine(command_line: LPCWSTR, command: *mut u32) -> Hr {
    ffi::boundary!(Opc, [command], {
        // SAFETY: the caller's contract: `command` NULL or writable, `command_line` NULL or
        // NUL-terminated.
        let (command, line) = unsafe { (ffi::out(command)?, ffi::in_string(command_line)?) };
        command.write(parse_command_line(&line)? as u32);
        Ok(S_OK)
    })
}

#[cfg(test)]
mod tests {
    use super::OpcServerCommand::*;
    use super::*;

    #[test]
    fn switches_are_recognised_in_any_case_and_form() {
        for line in [
            "/RegServer",
            "-regserver",
            "server.exe /REGSERVER",
            "\"C:\\My Server\\s.exe\" -RegServer",
        ] {
            assert_eq!(parse_command_line(line), Ok(Register), "{line}");
        }
        for line in ["/UnregServer", "x.exe -UNREGSERVER", "-unregserver /foo"] {
            assert_eq!(parse_command_line(line), Ok(Unregister), "{line}");
        }
        for line in ["-Embedding", "x.exe /embedding", "-Automation"] {
            assert_eq!(parse_command_line(line), Ok(Embedding), "{line}");
        }
        for line in [
            "",
            "x.exe",
            "RegServer",
            "/RegServerX",
            "\"/Reg Server\"",
            "C:\\regserver\\x.exe",
            "--RegServer",
        ] {
            assert_eq!(parse_command_line(line), Ok(None), "{line}");
        }
        assert_eq!(parse_command_line("/RegServer -UnregServer"), Err(E_INVALIDARG));
        assert_eq!(parse_command_line("-Embedding /RegServer"), Ok(Register));
    }

    #[test]
    fn program_paths_are_quoted_and_read_back_either_way() {
        let path = "C:\\Program Files\\OPC Tools\\x.exe";
        let line = command_line_of(path);
        assert_eq!(line, "\"C:\\Program Files\\OPC Tools\\x.exe\"");
        assert_eq!(program_path(&line), path);
        // Unquoted (as written before), with arguments, or given as a command line.
        assert_eq!(program_path(path), path);
        assert_eq!(program_path("\"C:\\a b\\x.exe\" -Embedding"), "C:\\a b\\x.exe");
        assert_eq!(
            command_line_of("\"C:\\a b\\x.exe\" -service"),
            "\"C:\\a b\\x.exe\" -service"
        );
        assert_eq!(program_path("\"unterminated"), "unterminated");
    }
}
